#include "pipeline/fusion_stage.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"
#include "acquisition/stats.h"
#include "surfels/render.h"

namespace gf {
namespace {

const char* SourceName(size_t source) {
  switch (static_cast<DepthSource>(source)) {
    case DepthSource::kSensor:
      return "sensor";
    case DepthSource::kStereo:
      return "stereo_fill";
    case DepthSource::kColmap:
      return "colmap";
    case DepthSource::kCarried:
      return "carried_fill";
    case DepthSource::kTransparent:
      return "transparent";
    default:
      return "none";
  }
}

}  // namespace

bool FusionStageOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.In("queue_capacity", queue_capacity, 1, kMaxFramesInMemory, kMoreFramesThanMemory)
      .In("count_every", count_every, 1, kMaxCaptureFrames, kMoreFramesThanACapture)
      .In("completion_max_gap_px", completion_max_gap_px, 0, kMaxImageSidePx, kLargerThanAnyImage)
      .In("completion_max_angle_deg", completion_max_angle_deg, 0, 90,
          "is more than a surface facing the camera can turn")
      .In("completion_min_support", completion_min_support, 0, kMaxCaptureFrames,
          kMoreFramesThanACapture)
      .In("completion_occluder_px", completion_occluder_px, 0, kMaxImageSidePx,
          kLargerThanAnyImage)
      .Above("completion_support_half", completion_support_half, 0, kMaxCaptureFrames,
             kMoreFramesThanACapture)
      .Part("fusion", fusion);
  return c.ok();
}

FusionStage::FusionStage(const Camera& camera, const FusionStageOptions& options,
                         std::vector<Variant> variants, PoseCorrections* corrections)
    : camera_(camera),
      options_(options),
      queue_(options.queue_capacity),
      corrections_(corrections) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  for (Variant& v : variants) {
    GF_CHECK(v.sink != nullptr, "every fusion variant needs a sink");
    maps_.push_back(
        {std::move(v), SurfelFusion(camera, options.fusion), {}, {}, {}, 0, 0, {}, 0, 0, {}});
  }
  worker_.Start("gf-fusion", [this] { Run(); });
}

FusionStage::~FusionStage() {
  Cancel();
  worker_.Join();
}

void FusionStage::OfferFrame(const RgbdFrame& frame, const SE3& world_from_camera, int keyframe,
                             SequencePoint at) {
  Item item;
  item.frame = frame;
  item.world_from_camera = world_from_camera;
  item.keyframe = keyframe;
  item.at = at;
  const bool queued =
      options_.drop_when_busy ? queue_.TryPush(std::move(item)) : queue_.Push(std::move(item));
  if (!queued) ++dropped_;
}

void FusionStage::OfferFill(const FilledKeyframe& filled, int keyframe) {
  if (!filled.record.failure.empty() || filled.fill.fill_mask.empty()) return;
  Item item;
  item.fill = true;
  item.frame = filled.key->frame;
  item.world_from_camera = filled.key->world_from_camera;
  item.keyframe = keyframe;
  item.filled_depth = filled.fill.filled_depth;
  item.confidence = filled.fill.confidence;
  // The keyframe's own stereo fill; carried pixels repeat earlier keyframes' own fills.
  item.fill_mask = filled.fill.fill_mask.clone();
  if (!options_.fuse_carried)
    item.fill_mask &= filled.fill.source == static_cast<uint8_t>(DepthSource::kStereo);
  if (!filled.fill.corroborated.empty())
    item.fill_mask.setTo(kCorroboratedFill,
                         (item.fill_mask != 0) & (filled.fill.corroborated != 0));
  std::lock_guard<std::mutex> lock(fills_mutex_);
  if (options_.drop_when_busy && fills_.size() >= static_cast<size_t>(options_.queue_capacity)) {
    ++dropped_;
    return;
  }
  item.produced_at = fills_processed_ + 1;
  fills_.push_back(std::move(item));
  fills_changed_.notify_all();
}

void FusionStage::FillsProcessed(int n) {
  std::lock_guard<std::mutex> lock(fills_mutex_);
  fills_processed_ = n;
  fills_changed_.notify_all();
}

void FusionStage::CloseFills() {
  std::lock_guard<std::mutex> lock(fills_mutex_);
  fills_closed_ = true;
  fills_changed_.notify_all();
}

void FusionStage::Finish(const std::function<bool()>& poll, const OutlineViews& views) {
  queue_.Close();
  while (!worker_.WaitFor(std::chrono::milliseconds(50)))
    if (poll && poll()) Cancel();
  worker_.Join();
  if (worker_.error()) std::rethrow_exception(worker_.error());
  for (Map& m : maps_) {
    const GlassOptions& glass = options_.fusion.glass;
    if (glass.enabled && glass.revolution.enabled) {
      m.revolutions = FitRevolutions(m.fusion.StableSurfels(), glass.revolution, &camera_, views);
      m.fusion.AddSurfels(m.revolutions.surfels);
    }
    Record(&m);
    m.variant.sink->WriteMap(m.fusion.StableSurfels());
  }
}

void FusionStage::Cancel() {
  cancelled_ = true;
  queue_.Close();
  std::lock_guard<std::mutex> lock(fills_mutex_);
  fills_changed_.notify_all();
}

void FusionStage::Run() {
  Item item;
  while (!cancelled_ && queue_.Pop(&item)) {
    CatchUp(item.at);
    if (cancelled_) break;
    FuseItem(item);
    ++frames_fused_;
    if (options_.predict) {
      // Rendered where the map is; handed back at the tracked pose (tracking's own frame).
      const SE3 world_from_camera =
          PoseCorrections::Lookup(applied_, item.keyframe) * item.world_from_camera;
      cv::Mat depth = maps_.front().fusion.RenderDepth(world_from_camera);
      std::lock_guard<std::mutex> lock(prediction_mutex_);
      prediction_depth_ = depth;
      prediction_pose_ = item.world_from_camera;
      prediction_frames_ = frames_fused_;
      prediction_ready_.notify_all();
    }
  }
  if (!cancelled_) {
    // The last corrections (loop closure has finished before the queue closes), then the fills
    // of the fill stage's last keyframes (it has finished too), in the order produced.
    if (corrections_ && corrections_->version() != applied_version_) {
      int version = 0;
      std::map<int, SE3> latest = corrections_->Snapshot(&version);
      ApplyCorrections(std::move(latest), version);
    }
    for (const Item& fill : TakeFills(std::numeric_limits<int>::max(), false)) FuseItem(fill);
  }
  std::lock_guard<std::mutex> lock(prediction_mutex_);
  prediction_closed_ = true;
  prediction_ready_.notify_all();
}

void FusionStage::CatchUp(const SequencePoint& at) {
  const bool in_sequence = !options_.drop_when_busy;
  if (corrections_) {
    int version = 0;
    std::map<int, SE3> latest =
        in_sequence ? corrections_->AtProcessed(at.loops, &version, [&] { return cancelled_.load(); })
                    : corrections_->Snapshot(&version);
    if (version != applied_version_) ApplyCorrections(std::move(latest), version);
  }
  for (const Item& fill :
       TakeFills(in_sequence ? at.fills : std::numeric_limits<int>::max(), in_sequence))
    FuseItem(fill);
}

std::vector<FusionStage::Item> FusionStage::TakeFills(int n, bool wait) {
  std::unique_lock<std::mutex> lock(fills_mutex_);
  if (wait)
    fills_changed_.wait(lock, [&] { return cancelled_ || fills_closed_ || fills_processed_ >= n; });
  std::vector<Item> due;
  while (!fills_.empty() && fills_.front().produced_at <= n) {
    due.push_back(std::move(fills_.front()));
    fills_.pop_front();
  }
  return due;
}

void FusionStage::FuseItem(const Item& item) {
  newest_keyframe_ = std::max(newest_keyframe_, item.keyframe);
  const SE3 world_from_camera =
      PoseCorrections::Lookup(applied_, item.keyframe) * item.world_from_camera;
  for (Map& m : maps_) Fuse(item, world_from_camera, &m);
}

void FusionStage::ApplyCorrections(std::map<int, SE3> latest, int version) {
  std::vector<SE3> change;
  for (int k = 0; k <= newest_keyframe_; ++k)
    change.push_back(PoseCorrections::Lookup(latest, k) *
                     PoseCorrections::Lookup(applied_, k).Inverse());
  const auto start = std::chrono::steady_clock::now();
  for (Map& m : maps_) m.fusion.MoveWithKeyframes(change);
  applied_ = std::move(latest);
  applied_version_ = version;
  ++corrections_applied_;
  spdlog::debug(
      "fusion: maps moved with {} keyframes' corrections in {:.1f} ms", change.size(),
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
}

void FusionStage::PrepareRenders() {
  if (!maps_.empty()) maps_.front().fusion.SettleChunks();  // (none: RenderFills says so)
}

MapCompletion FusionStage::RenderFills(const SE3& world_from_camera) {
  GF_CHECK(!maps_.empty(), "fusion stage: no map to render");
  const double margin = options_.fusion.free_space_margin;
  MapView view = maps_.front().fusion.RenderView(world_from_camera, margin);
  MapCompletion offer;
  offer.depth = view.depth;
  offer.depth.setTo(0, view.source == static_cast<uint8_t>(DepthSource::kSensor));
  if (options_.completion_max_gap_px > 0) {
    const cv::Mat drawn = offer.depth > 0;
    CloseSplatGaps(&offer.depth, view.source == static_cast<uint8_t>(DepthSource::kNone),
                   options_.completion_max_gap_px, margin);
    // A closed gap is as well known as the least known disc around it (the discs that enclose
    // it lie at most max_gap_px + 1 pixels away).
    const cv::Mat closed = (offer.depth > 0) & ~drawn;
    const int reach = options_.completion_max_gap_px + 1;
    const cv::Mat window =
        cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * reach + 1, 2 * reach + 1));
    constexpr float kNone = std::numeric_limits<float>::max();
    for (cv::Mat* m : {&view.facing, &view.support}) {
      cv::Mat least = m->clone();
      least.setTo(kNone, ~drawn);
      cv::erode(least, least, window);
      least.setTo(0, least == kNone);  // (none within reach: not confirmed)
      least.copyTo(*m, closed);
    }
  }
  const cv::Mat confirmed =
      (offer.depth > 0) &
      (view.facing >= std::cos(options_.completion_max_angle_deg * M_PI / 180.0)) &
      (view.support >= options_.completion_min_support);
  offer.depth.setTo(0, ~confirmed);
  cv::Mat facing = cv::max(view.facing, 0.0);
  cv::Mat support_share = view.support / (view.support + options_.completion_support_half);
  // At least one step of the 8-bit image it is written to, so that every completed pixel shows.
  offer.confidence = cv::max(facing.mul(support_share), 1.0 / 255);
  offer.confidence.setTo(0, ~confirmed);
  offer.occluder_px = options_.completion_occluder_px;
  offer.occluder_margin = margin;
  if (options_.fusion.glass.enabled)
    offer.glass = view.source == static_cast<uint8_t>(DepthSource::kTransparent);
  return offer;
}

bool FusionStage::Prediction(int frames, std::chrono::milliseconds timeout, cv::Mat* depth,
                             SE3* world_from_camera) {
  std::unique_lock<std::mutex> lock(prediction_mutex_);
  auto ready = [&] { return prediction_closed_ || prediction_frames_ >= frames; };
  if (options_.drop_when_busy)
    prediction_ready_.wait_for(lock, timeout, ready);
  else
    prediction_ready_.wait(lock, ready);  // recorded input: the same model every run
  if (prediction_depth_.empty() || prediction_frames_ < frames) return false;
  *depth = prediction_depth_;
  *world_from_camera = prediction_pose_;
  return true;
}

void FusionStage::Fuse(const Item& item, const SE3& world_from_camera, Map* m) {
  if (item.fill && !m->variant.fills) return;
  try {
    FusionStats s;
    if (item.fill) {
      s = m->fusion.FuseFill(item.frame, item.filled_depth, item.fill_mask, item.confidence,
                             DepthSource::kStereo, world_from_camera, item.keyframe);
      m->fill_ms.push_back(s.ms);
    } else {
      s = m->fusion.FuseFrame(item.frame, world_from_camera, item.keyframe);
      m->frame_ms.push_back(s.ms);
      m->redundant += s.redundant;
      m->over_budget += s.over_budget;
      if (m->fusion.frames() % options_.count_every == 0) Record(m);
    }
    spdlog::debug("{} {} {}: {}", m->variant.name, item.fill ? "fill" : "frame",
                  KeyframeName(item.frame), s.BriefReport());
  } catch (const std::exception& e) {
    ++(item.fill ? m->failed_fills : m->failed_frames);
    if (m->first_failure.empty()) m->first_failure = e.what();
    spdlog::warn("fusion ({}): {} {} skipped: {}", m->variant.name,
                 item.fill ? "fill of keyframe" : "frame", KeyframeName(item.frame), e.what());
  }
}

void FusionStage::Record(Map* m) const {
  const SurfelCounts c = m->fusion.Counts();
  m->over_time.push_back({m->fusion.frames(), c.total_stable(),
                          c.stable[static_cast<int>(DepthSource::kSensor)],
                          c.stable[static_cast<int>(DepthSource::kStereo)],
                          c.unstable[0] + c.unstable[1] + c.unstable[2] + c.unstable[3] +
                              c.unstable[4]});
}

SurfelReport FusionStage::Report(size_t index) const {
  const Map& m = maps_.at(index);
  const SurfelCounts c = m.fusion.Counts();
  SurfelReport r;
  r.count = c.total_stable();
  for (size_t k = 1; k < c.stable.size(); ++k) {
    r.by_source.push_back({SourceName(k), c.stable[k]});
    r.area_m2.push_back({SourceName(k), c.stable_area_m2[k]});
    r.unstable.push_back({SourceName(k), c.unstable[k]});
  }
  r.bytes_per_surfel = sizeof(Surfel);
  r.memory_bytes = m.fusion.MemoryBytes();
  r.count_over_time = m.over_time;
  r.variant = m.variant.name;
  r.fills_fused = m.fill_ms.size();
  r.frame_ms = StepTimes::Of(m.frame_ms);
  r.fill_ms = StepTimes::Of(m.fill_ms);
  r.merged_as_copies = m.redundant;
  r.budget = options_.fusion.max_surfels;
  r.removed_over_budget = m.over_budget;
  r.failed_frames = m.failed_frames;
  r.failed_fills = m.failed_fills;
  if (!m.first_failure.empty()) r.first_failure = m.first_failure;
  r.dropped_items = dropped_.load();
  r.corrections_applied = corrections_applied_;
  r.glass_objects = m.revolutions.objects;
  r.glass_shapes = static_cast<int>(m.revolutions.shapes.size());
  for (const RevolutionShape& shape : m.revolutions.shapes)
    r.glass_shapes_from_outlines += shape.from_outline;
  r.glass_shape_surfels = static_cast<long>(m.revolutions.surfels.size());
  return r;
}

}  // namespace gf
