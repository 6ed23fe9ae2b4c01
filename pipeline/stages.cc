#include "pipeline/stages.h"

#include <spdlog/spdlog.h>

#include <chrono>

#include "acquisition/errors.h"
#include "acquisition/stats.h"

namespace gf {
namespace {

using Clock = std::chrono::steady_clock;

double Ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// Frames whose depth decides whether the depth scale is plausible (DepthScaleProblem).
constexpr size_t kDepthScaleFrames = 10;

}  // namespace

ReadStage::ReadStage(FrameSource* source, int first_frame, int end_frame,
                     BoundedQueue<FrameItem>* queue)
    : source_(source), first_frame_(first_frame), end_frame_(end_frame), queue_(queue) {
  thread_.Start("gf-read", [this] { Run(); });
}

ReadStage::~ReadStage() {
  Stop();
  thread_.Join();
}

void ReadStage::Stop() {
  stop_ = true;
  queue_->Close();
}

void ReadStage::Run() {
  struct CloseAtEnd {
    BoundedQueue<FrameItem>* queue;
    ~CloseAtEnd() { queue->Close(); }
  } close{queue_};
  for (int index = 0; !stop_; ++index) {
    FrameItem item;
    const auto t0 = Clock::now();
    try {
      if (end_frame_ >= 0 && index >= end_frame_) break;
      if (!source_->Next(&item.frame)) break;
    } catch (...) {
      item.error = std::current_exception();
      queue_->Push(std::move(item));
      break;
    }
    item.read_ms = Ms(t0, Clock::now());
    if (index < first_frame_) continue;
    if (!queue_->Push(std::move(item))) break;
  }
}

TrackStage::TrackStage(const FrameSource& source, const TrackerOptions& options,
                       const std::string& camera_file, BoundedQueue<FrameItem>* queue,
                       FillStage* fill, FusionStage* fusion, LoopClosureStage* loop,
                       bool frame_to_model)
    : source_(source),
      options_(options),
      camera_file_(camera_file),
      queue_(queue),
      fill_(fill),
      fusion_(fusion),
      loop_(loop),
      frame_to_model_(frame_to_model && fusion != nullptr) {
  thread_.Start("gf-track", [this] { Run(); });
}

TrackStage::~TrackStage() {
  Stop();
  thread_.Join();
}

void TrackStage::Stop() { stop_ = true; }

void TrackStage::Run() {
  FrameToKeyframeTracker tracker(source_.camera(), ForSensor(options_, source_.camera_file()));
  tracker.SetRelocaliser(loop_);
  FrameItem item;
  while (!stop_ && queue_->Pop(&item)) {
    if (item.error) std::rethrow_exception(item.error);
    CheckDepthScale(item.frame);
    record_.read_ms.push_back(item.read_ms);
    if (frame_to_model_ && offered_to_fusion_ > 0) {
      // The model of every frame so far, seen from the last one's pose. A model that does not
      // arrive in time (the fusion stage dropped frames, live) leaves this frame to its keyframe.
      cv::Mat depth;
      SE3 pose;
      if (fusion_->Prediction(offered_to_fusion_, std::chrono::seconds(2), &depth, &pose))
        tracker.SetModelReference(depth, pose);
    }
    Track(item.frame, &tracker);
    record_.keyframes = tracker.keyframes();
    ++frames_;
  }
}

void TrackStage::Track(const RgbdFrame& frame, FrameToKeyframeTracker* tracker) {
  const auto t0 = Clock::now();
  const TrackingResult r = tracker->Track(frame);
  record_.track_ms.push_back(Ms(t0, Clock::now()));
  const int keyframe = tracker->keyframes() - 1;  // the one this frame was tracked against
  record_.relocalised += r.status == TrackingStatus::kRelocalised;
  record_.restarted += r.status == TrackingStatus::kRestarted;
  if (r.status != TrackingStatus::kTracking && r.status != TrackingStatus::kInitialized)
    spdlog::debug("frame {} ({}): {}", frame.index, frame.timestamp_text, r.BriefReport());
  // The depth the pose places: moved to the stamp's instant where tracking modelled the rolling
  // shutter (the sensor's holes stay holes). Fusion and the fill use it, so that the fill's
  // validation and free-space checks agree with the map; the fill's outputs keep the sensor's
  // pixels as measured.
  RgbdFrame placed = frame;
  if (!r.depth_at_stamp.empty()) {
    placed.depth = r.depth_at_stamp.clone();  // may share its pixels with r.tracked_depth
    if (!frame.hole_mask.empty()) placed.depth.setTo(0.f, frame.hole_mask);
  }
  if (r.new_keyframe) OfferKeyframe(frame, placed, r, keyframe);
  ++record_.frames;
  if (!r.has_pose()) {
    // Lost frames have no pose: not in the trajectory, not fused.
    ++record_.lost;
    record_.lost_frames.push_back(KeyframeName(frame));
    return;
  }
  if (fusion_) {
    fusion_->OfferFrame(placed, r.world_from_camera, keyframe, handed_);
    ++offered_to_fusion_;
  }
  record_.trajectory.push_back({frame.timestamp, frame.timestamp_text, r.world_from_camera});
  record_.keyframe.push_back(keyframe);
  record_.names.push_back(KeyframeName(frame));
}

void TrackStage::OfferKeyframe(const RgbdFrame& frame, const RgbdFrame& placed,
                               const TrackingResult& r, int keyframe) {
  if (fill_ && r.has_pose()) {
    if (frame.color.empty())
      throw InputError(frame.depth_path.empty() ? source_.Input() : frame.depth_path,
                       "the stereo fill needs colour images (or --no-fill)");
    const bool moved = !r.depth_at_stamp.empty();  // then placed.depth is its own copy
    handed_.fills +=
        fill_->Offer(placed, r.world_from_camera, keyframe, moved ? frame.depth : cv::Mat());
  }
  if (!loop_) return;
  using Link = LoopKeyframeItem::Link;
  LoopKeyframeItem item;
  item.id = keyframe;
  item.frame = frame;
  item.frame.depth = r.tracked_depth;  // loop closure aligns what tracking aligned
  item.world_from_camera = r.world_from_camera;
  item.features = r.features;
  item.linked_to = last_keyframe_;
  if (r.status == TrackingStatus::kInitialized) {
    item.link = Link::kFirst;
  } else if (r.status == TrackingStatus::kRelocalised) {
    item.link = Link::kRelocalised;
    item.linked_to = r.relocalisation->keyframe;
    item.linked_from_this = r.relocalisation->keyframe_from_camera;
    item.information = r.relocalisation->information;
  } else if (r.status == TrackingStatus::kRestarted) {
    item.link = Link::kRestarted;
  } else {
    // Tracked against the previous keyframe: ICP's alignment is the odometry edge.
    item.link = Link::kOdometry;
    item.linked_from_this = last_keyframe_pose_.Inverse() * r.world_from_camera;
    item.information = r.icp.information;
  }
  last_keyframe_ = keyframe;
  last_keyframe_pose_ = r.world_from_camera;
  handed_.loops += loop_->Offer(std::move(item));
}

void TrackStage::CheckDepthScale(const RgbdFrame& frame) {
  std::vector<double>& medians = record_.median_depths;
  if (frame.median_return_m <= 0 || medians.size() >= kDepthScaleFrames) return;
  medians.push_back(frame.median_return_m);
  if (medians.size() < kDepthScaleFrames) return;
  const std::string problem = DepthScaleProblem(Median(medians), source_.depth_convention());
  if (!problem.empty()) throw InputError(camera_file_, problem);
}

}  // namespace gf
