#include "registration/tracker.h"

#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "acquisition/errors.h"

namespace gf {

bool KeyframePolicy::Check(std::string* message) const {
  if (!(max_rotation_deg > 0) || !(max_translation_m > 0) ||
      !(min_overlap >= 0 && min_overlap <= 1) || min_feature_inliers < 0) {
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
  if (!(restart_m > 0) || !(restart_deg > 0)) {
    if (message) *message = "restart_m and restart_deg must be positive";
    return false;
  }
  return icp.Check(message) && keyframes.Check(message) && surf.Check(message) &&
         match.Check(message) && ransac.Check(message);
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

FrameToKeyframeTracker::Features FrameToKeyframeTracker::ExtractFeatures(
    const RgbdFrame& frame) const {
  Features f;
  if (!options_.use_features || frame.color.empty()) return f;
  cv::Mat gray;
  cv::cvtColor(frame.color, gray, cv::COLOR_BGR2GRAY);
  SurfFeatures surf = DetectAndDescribeSurf(gray, options_.surf);
  f.keypoints = std::move(surf.keypoints);
  f.descriptors = surf.descriptors;
  for (const cv::KeyPoint& k : f.keypoints) {
    const int u = static_cast<int>(std::lround(k.pt.x)), v = static_cast<int>(std::lround(k.pt.y));
    const float z = (u >= 0 && v >= 0 && u < frame.depth.cols && v < frame.depth.rows)
                        ? frame.depth.at<float>(v, u)
                        : 0.f;
    f.points.push_back(z > 0 ? camera_.BackProject({k.pt.x, k.pt.y}, z)
                             : Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
  }
  return f;
}

void FrameToKeyframeTracker::SetModelReference(const cv::Mat& depth,
                                               const SE3& world_from_reference) {
  GF_CHECK(depth.type() == CV_32FC1 && depth.cols == camera_.width && depth.rows == camera_.height,
           "the model's depth must be CV_32F of the camera's size");
  model_ = BuildDepthPyramid(depth, camera_, options_.pyramid_levels);
  world_from_model_ = world_from_reference;
}

TrackingResult FrameToKeyframeTracker::Track(const RgbdFrame& frame) {
  TrackingResult result;
  const DepthPyramid model = std::move(model_);  // for this frame only
  model_ = DepthPyramid();
  DepthPyramid current = BuildDepthPyramid(frame.depth, camera_, options_.pyramid_levels);
  Features features = ExtractFeatures(frame);
  if (!initialized_) {
    initialized_ = true;
    keyframe_features_ = std::move(features);
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
  SE3 keyframe_from_predicted = world_from_keyframe_.Inverse() * predicted;
  std::vector<FeatureCorrespondence> correspondences;
  if (!features.keypoints.empty() && !keyframe_features_.keypoints.empty()) {
    const std::vector<cv::DMatch> matches =
        MatchDescriptors(features.keypoints, features.descriptors, keyframe_features_.keypoints,
                         keyframe_features_.descriptors, options_.match);
    std::vector<Eigen::Vector3d> source, target;
    std::vector<const cv::DMatch*> used;
    for (const cv::DMatch& m : matches) {
      const Eigen::Vector3d& p = features.points[m.queryIdx];
      const Eigen::Vector3d& q = keyframe_features_.points[m.trainIdx];
      if (!p.allFinite() || !q.allFinite()) continue;
      source.push_back(p);
      target.push_back(q);
      used.push_back(&m);
    }
    result.ransac = EstimateRigidRansac(source, target, options_.ransac);
    if (result.ransac.success) {
      for (int i : result.ransac.inlier_indices) {
        const cv::KeyPoint& k = keyframe_features_.keypoints[used[i]->trainIdx];
        correspondences.push_back({source[i], Eigen::Vector2d(k.pt.x, k.pt.y)});
      }
      const SE3 disagreement = keyframe_from_predicted.Inverse() * result.ransac.target_from_source;
      if (disagreement.TranslationNorm() > options_.restart_m ||
          disagreement.RotationAngle() * 180.0 / M_PI > options_.restart_deg)
        keyframe_from_predicted = result.ransac.target_from_source;
    }
  }
  result.icp =
      AlignPointToPlane(keyframe_, current, keyframe_from_predicted, options_.icp, correspondences);
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
    keyframe_features_ = std::move(features);
    world_from_keyframe_ = world_from_previous_;
    velocity_ = SE3();
    ++keyframes_;
    result.new_keyframe = true;
    return result;
  }
  result.status = TrackingStatus::kTracking;
  SE3 keyframe_from_current = result.icp.reference_from_current;
  result.world_from_camera = world_from_keyframe_ * keyframe_from_current;
  if (!model.depth.empty()) {
    // Refine against the model, which has fused every earlier frame (less drift than one keyframe).
    const SE3 model_from_current = world_from_model_.Inverse() * result.world_from_camera;
    const IcpSummary refined = AlignPointToPlane(model, current, model_from_current, options_.icp);
    const SE3 step = model_from_current.Inverse() * refined.reference_from_current;
    if (refined.success && step.TranslationNorm() <= options_.max_jump_m &&
        step.RotationAngle() * 180.0 / M_PI <= options_.max_jump_deg) {
      result.world_from_camera = world_from_model_ * refined.reference_from_current;
      keyframe_from_current = world_from_keyframe_.Inverse() * result.world_from_camera;
      result.model_refined = true;
    }
  }
  velocity_ = world_from_previous_.Inverse() * result.world_from_camera;
  world_from_previous_ = result.world_from_camera;
  const KeyframePolicy& k = options_.keyframes;
  const bool few_features = options_.use_features && !frame.color.empty() &&
                            result.ransac.inliers < k.min_feature_inliers;
  if (keyframe_from_current.RotationAngle() * 180.0 / M_PI > k.max_rotation_deg ||
      keyframe_from_current.TranslationNorm() > k.max_translation_m ||
      result.overlap < k.min_overlap || few_features) {
    keyframe_ = std::move(current);
    keyframe_features_ = std::move(features);
    world_from_keyframe_ = result.world_from_camera;
    ++keyframes_;
    result.new_keyframe = true;
  }
  return result;
}

}  // namespace gf
