#include "pipeline/fill_stage.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"

namespace gf {

bool FillStageOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.In("queue_capacity", queue_capacity, 1, kMaxFramesInMemory, kMoreFramesThanMemory);
  return c.ok() && Filler().Check(message);
}

KeyframeFillerOptions FillStageOptions::Filler() const {
  KeyframeFillerOptions f{pairs, stereo, carry};
  f.pairs.geometry = f.stereo.geometry = geometry;
  return f;
}

FillStage::FillStage(const Camera& camera, const FillStageOptions& options, RunSink* sink,
                     FusionStage* fusion)
    : camera_(camera),
      options_(options),
      sink_(sink),
      fusion_(fusion),
      queue_(options.queue_capacity) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  GF_CHECK(sink != nullptr, "the fill stage needs a sink");
  filler_ = std::make_unique<KeyframeFiller>(camera_, options_.Filler());
  writer_.Start("gf-fill-write", [this] { RunWriting(filler_.get()); });
  stereo_worker_.Start("gf-stereo", [this] { RunStereo(filler_.get()); });
  worker_.Start("gf-fill", [this] { RunPairing(filler_.get()); });
}

FillStage::~FillStage() {
  Cancel();
  worker_.Join();
  stereo_worker_.Join();
  writer_.Join();
}

bool FillStage::Offer(const RgbdFrame& frame, const SE3& world_from_camera, int keyframe,
                      const cv::Mat& measured_depth) {
  Offered item{frame, world_from_camera, keyframe, measured_depth};
  if (options_.drop_when_busy ? queue_.TryPush(std::move(item)) : queue_.Push(std::move(item))) {
    ++accepted_;
    return true;
  }
  if (stopped_ || cancelled_) {
    ++not_filled_;
    spdlog::debug("fill: keyframe {} not filled (the fill stage has stopped)", KeyframeName(frame));
  } else {
    ++dropped_;
    spdlog::debug("fill: keyframe {} dropped (stereo worker busy: {} keyframes queued)",
                  KeyframeName(frame), options_.queue_capacity);
  }
  return false;
}

void FillStage::Finish(const std::function<bool()>& poll) {
  queue_.Close();
  while (!writer_.WaitFor(std::chrono::milliseconds(50)))
    if (poll && poll()) Cancel();
  worker_.Join();
  stereo_worker_.Join();
  writer_.Join();
  for (const StageThread* t : {&writer_, &stereo_worker_, &worker_})
    if (t->error()) std::rethrow_exception(t->error());
}

void FillStage::Cancel() {
  cancelled_ = true;
  CloseQueues();
}

void FillStage::CloseQueues() {
  queue_.Close();
  paired_.Close();
  stereo_done_.Close();
}

void FillStage::RunPairing(KeyframeFiller* filler) {
  EndOfBatches done{this, &paired_};  // however it ends, the stereo thread gets no more
  Offered item;
  int processed = 0;
  while (!cancelled_ && queue_.Pop(&item)) {
    {
      std::lock_guard<std::mutex> lock(order_mutex_);
      if (!item.measured_depth.empty()) measured_of_[item.frame.index] = item.measured_depth;
      keyframe_of_.push_back(item.keyframe);  // the filler numbers keyframes as they arrive
    }
    if (!paired_.Push({filler->Pair(item.frame, item.world_from_camera), ++processed})) break;
  }
  if (!cancelled_) paired_.Push({filler->PairRest(), 0});
  done.ok = true;
}

void FillStage::RunStereo(const KeyframeFiller* filler) {
  EndOfBatches done{this, &stereo_done_};
  Batch batch;
  while (!cancelled_ && paired_.Pop(&batch)) {
    for (FillTask& task : batch.tasks) {
      if (cancelled_) break;
      filler->Stereo(&task);
    }
    if (!stereo_done_.Push(std::move(batch))) break;
  }
  done.ok = true;
}

void FillStage::RunWriting(KeyframeFiller* filler) {
  // However the worker ends, the fusion stage stops waiting for its fills, and the other threads
  // stop.
  struct Stopped {
    FillStage* stage;
    ~Stopped() {
      stage->stopped_ = true;
      stage->CloseQueues();
      if (stage->fusion_) stage->fusion_->CloseFills();
    }
  } stopped{this};
  Batch batch;
  while (!cancelled_ && stereo_done_.Pop(&batch)) {
    for (FillTask& task : batch.tasks) {
      if (cancelled_) break;
      if (!task.failed && !task.result.key) continue;  // left by a cancel
      Write(filler->Carry(std::move(task)));
    }
    if (fusion_ && batch.processed > 0 && !cancelled_) fusion_->FillsProcessed(batch.processed);
  }
  std::lock_guard<std::mutex> lock(order_mutex_);
  measured_of_.clear();  // keyframes left unwritten by a cancel
}

void FillStage::Write(const FilledKeyframe& k) {
  const KeyframeFill& r = k.record;
  if (!r.failure.empty()) spdlog::warn("fill: keyframe {} skipped: {}", r.timestamp, r.failure);
  if (!k.stereo.rectification.r_left.empty())
    spdlog::debug("fill {}: {}", r.timestamp, k.stereo.rectification.BriefReport());
  if (k.partner) spdlog::debug("fill {}: {}", r.timestamp, k.stereo.BriefReport());
  if (r.carried_pixels + r.corrected_pixels > 0)
    spdlog::debug("fill {}: {}", r.timestamp, k.fill.BriefReport());
  cv::Mat measured_depth;
  int tracker_keyframe = -1;
  {
    std::lock_guard<std::mutex> lock(order_mutex_);
    const auto measured = measured_of_.find(k.key->frame.index);
    if (measured != measured_of_.end()) {
      measured_depth = measured->second;
      measured_of_.erase(measured);
    }
    const int id = k.key->id;
    tracker_keyframe =
        id >= 0 && id < static_cast<int>(keyframe_of_.size()) && keyframe_of_[id] >= 0
            ? keyframe_of_[id]
            : id;
  }
  if (measured_depth.empty()) {
    sink_->WriteKeyframe(r.timestamp, k.key->frame, k.fill);  // a write failure stops the stage
  } else {
    // The sensor's pixels as measured; the fill's where it measured nothing.
    RgbdFrame frame = k.key->frame;
    frame.depth = measured_depth;
    CarriedFillResult written = k.fill;
    written.filled_depth = k.fill.filled_depth.clone();
    measured_depth.copyTo(written.filled_depth, written.fill_mask == 0);
    sink_->WriteKeyframe(r.timestamp, frame, written);
  }
  if (fusion_) fusion_->OfferFill(k, tracker_keyframe);
  std::lock_guard<std::mutex> lock(done_mutex_);
  done_.push_back(r);
  ++done_count_;
}

std::vector<KeyframeFill> FillStage::keyframes() const {
  std::lock_guard<std::mutex> lock(done_mutex_);
  return done_;
}

FillReport FillStage::Report() const {
  const std::vector<KeyframeFill> done = keyframes();
  // Queued but never filled (the run stopped first), and offered after the stage stopped.
  return FillReport::Of(done, dropped_, accepted_ - static_cast<int>(done.size()) + not_filled_);
}

}  // namespace gf
