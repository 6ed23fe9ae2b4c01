#include "registration/tracker.h"

#include <cmath>
#include <cstdio>

#include "acquisition/errors.h"

namespace gf {

bool KeyframePolicy::Check(std::string* message) const {
  if (!(max_rotation_deg > 0) || !(max_translation_m > 0) ||
      !(min_overlap >= 0 && min_overlap <= 1)) {
    if (message) *message = "keyframe policy: need positive thresholds and min_overlap in [0, 1]";
    return false;
  }
  return true;
}

bool TrackerOptions::Check(std::string* message) const {
  if (pyramid_levels < static_cast<int>(icp.iterations.size())) {
    if (message) *message = "pyramid_levels must cover icp.iterations";
    return false;
  }
  if (!(max_jump_m > 0) || !(max_jump_deg > 0)) {
    if (message) *message = "max_jump_m and max_jump_deg must be positive";
    return false;
  }
  return icp.Check(message) && keyframes.Check(message);
}

const char* TrackingStatusName(TrackingStatus status) {
  switch (status) {
    case TrackingStatus::kInitialized:
      return "initialized";
    case TrackingStatus::kTracking:
      return "tracking";
    case TrackingStatus::kLost:
      return "lost";
  }
  return "unknown";
}

std::string TrackingResult::BriefReport() const {
  char buffer[320];
  std::snprintf(buffer, sizeof(buffer), "%s%s, overlap %.2f; %s", TrackingStatusName(status),
                new_keyframe ? " (new keyframe)" : "", overlap, icp.BriefReport().c_str());
  return buffer;
}

FrameToKeyframeTracker::FrameToKeyframeTracker(const Camera& camera, const TrackerOptions& options)
    : camera_(camera), options_(options) {
  std::string problem;
  GF_CHECK(options_.Check(&problem), problem);
}

TrackingResult FrameToKeyframeTracker::Track(const RgbdFrame& frame) {
  TrackingResult result;
  DepthPyramid current = BuildDepthPyramid(frame.depth, camera_, options_.pyramid_levels);
  if (!initialized_) {
    initialized_ = true;
    keyframe_ = std::move(current);
    world_from_keyframe_ = world_from_previous_ = SE3();
    velocity_ = SE3();
    ++keyframes_;
    result.status = TrackingStatus::kInitialized;
    result.new_keyframe = true;
    result.overlap = 1.0;
    return result;
  }
  const SE3 predicted = world_from_previous_ * (options_.constant_velocity ? velocity_ : SE3());
  const SE3 keyframe_from_predicted = world_from_keyframe_.Inverse() * predicted;
  result.icp = AlignPointToPlane(keyframe_, current, keyframe_from_predicted, options_.icp);
  result.overlap = result.icp.valid_points ? static_cast<double>(result.icp.overlapping_points) /
                                                 result.icp.valid_points
                                           : 0.0;
  const SE3 correction = keyframe_from_predicted.Inverse() * result.icp.reference_from_current;
  const bool jumped = correction.TranslationNorm() > options_.max_jump_m ||
                      correction.RotationAngle() * 180.0 / M_PI > options_.max_jump_deg;
  if (!result.icp.success || jumped) {
    // Lost: keep the last good pose, restart from this frame as a keyframe there.
    result.status = TrackingStatus::kLost;
    result.world_from_camera = world_from_previous_;
    keyframe_ = std::move(current);
    world_from_keyframe_ = world_from_previous_;
    velocity_ = SE3();
    ++keyframes_;
    result.new_keyframe = true;
    return result;
  }
  result.status = TrackingStatus::kTracking;
  const SE3 keyframe_from_current = result.icp.reference_from_current;
  result.world_from_camera = world_from_keyframe_ * keyframe_from_current;
  velocity_ = world_from_previous_.Inverse() * result.world_from_camera;
  world_from_previous_ = result.world_from_camera;
  const KeyframePolicy& k = options_.keyframes;
  if (keyframe_from_current.RotationAngle() * 180.0 / M_PI > k.max_rotation_deg ||
      keyframe_from_current.TranslationNorm() > k.max_translation_m ||
      result.overlap < k.min_overlap) {
    keyframe_ = std::move(current);
    world_from_keyframe_ = result.world_from_camera;
    ++keyframes_;
    result.new_keyframe = true;
  }
  return result;
}

}  // namespace gf
