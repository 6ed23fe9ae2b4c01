#include "registration/tracker.h"

#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"
#include "registration/rolling_shutter.h"

namespace gf {

bool KeyframePolicy::Check(std::string* message) const {
  FieldCheck c(message);
  c.Above("max_rotation_deg", max_rotation_deg, 0, kMaxAngleDeg, kMoreThanAHalfTurn)
      .Above("max_translation_m", max_translation_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .In("min_overlap", min_overlap, 0, 1, kMoreThanOne)
      .In("min_feature_inliers", min_feature_inliers, 0, kMaxImagePixels, kMoreThanAnImagesPixels);
  return c.ok();
}

bool TrackerOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.In("pyramid_levels", pyramid_levels, 1, kMaxPyramidLevels, kMoreLevelsThanAnyPyramid)
      .Require(pyramid_levels >= static_cast<int>(icp.iterations.size()),
               "pyramid_levels must cover icp.iterations")
      .Above("max_jump_m", max_jump_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("max_jump_deg", max_jump_deg, 0, kMaxAngleDeg, kMoreThanAHalfTurn)
      // A readout of a second or more is no video sensor's.
      .In("depth_readout_s", depth_readout_s, 0, 1, "is a readout longer than a second")
      .Require(depth_readout_s < 1, "depth_readout_s must be less than a second")
      .In("relocalise_frames", relocalise_frames, 0, kMaxCaptureFrames, kMoreFramesThanACapture)
      // A full turn per metre travelled: no drift worth simulating is larger.
      .In("simulated_drift_deg_per_m", simulated_drift_deg_per_m, -360, 360,
          "is more than a full turn per metre")
      .Above("restart_m", restart_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("restart_deg", restart_deg, 0, kMaxAngleDeg, kMoreThanAHalfTurn)
      .Part("icp", icp)
      .Part("keyframes", keyframes)
      .Part("surf", surf)
      .Part("match", match)
      .Part("ransac", ransac);
  return c.ok();
}

const char* TrackingStatusName(TrackingStatus status) {
  switch (status) {
    case TrackingStatus::kInitialized:
      return "initialized";
    case TrackingStatus::kTracking:
      return "tracking";
    case TrackingStatus::kLost:
      return "lost";
    case TrackingStatus::kRelocalised:
      return "relocalised";
    case TrackingStatus::kRestarted:
      return "restarted";
  }
  return "unknown";
}

TrackerOptions ForSensor(TrackerOptions options, const CameraFile& camera) {
  if (camera.depth_readout_s) options.depth_readout_s = *camera.depth_readout_s;
  if (camera.depth_readout_order) options.depth_readout_order = *camera.depth_readout_order;
  return options;
}

std::string TrackingResult::BriefReport() const {
  char buffer[320];
  std::snprintf(buffer, sizeof(buffer), "%s%s, overlap %.2f; %s", TrackingStatusName(status),
                new_keyframe ? " (new keyframe)" : "", overlap, icp.BriefReport().c_str());
  return buffer;
}

FrameToKeyframeTracker::FrameToKeyframeTracker(const Camera& camera, const TrackerOptions& options)
    : camera_(camera),
      pinhole_(camera),
      shutter_(camera, options.depth_readout_s, options.depth_readout_order),
      options_(options) {
  std::string problem;
  GF_CHECK(options_.Check(&problem), problem);
  pinhole_.distortion = {};
  if (camera.HasDistortion()) camera.UndistortionMaps(&undistort_x_, &undistort_y_);
}

cv::Mat FrameToKeyframeTracker::UndistortedDepth(const cv::Mat& depth) const {
  if (undistort_x_.empty() || depth.empty()) return depth;
  cv::Mat out;
  cv::remap(depth, out, undistort_x_, undistort_y_, cv::INTER_NEAREST, cv::BORDER_CONSTANT, 0);
  return out;
}

RgbdFrame FrameToKeyframeTracker::Undistorted(const RgbdFrame& frame) const {
  if (undistort_x_.empty()) return frame;
  // New images: the frame's own are shared with the other stages and must not change.
  RgbdFrame f = frame;
  f.depth = UndistortedDepth(frame.depth);
  f.color = cv::Mat();
  f.hole_mask = cv::Mat();
  if (!frame.color.empty())
    cv::remap(frame.color, f.color, undistort_x_, undistort_y_, cv::INTER_LINEAR,
              cv::BORDER_CONSTANT);
  if (!frame.hole_mask.empty())
    cv::remap(frame.hole_mask, f.hole_mask, undistort_x_, undistort_y_, cv::INTER_NEAREST,
              cv::BORDER_CONSTANT, 0);
  return f;
}

void FrameToKeyframeTracker::SetModelReference(const cv::Mat& depth,
                                               const SE3& world_from_reference) {
  GF_CHECK(depth.type() == CV_32FC1 && depth.cols == camera_.width && depth.rows == camera_.height,
           "the model's depth must be CV_32F of the camera's size");
  model_ = BuildDepthPyramid(UndistortedDepth(depth), pinhole_, options_.pyramid_levels);
  world_from_model_ = world_from_reference;
}

bool FrameToKeyframeTracker::AlignToKeyframe(const DepthPyramid& reference,
                                             const DepthPyramid& current,
                                             const FrameFeatures& features,
                                             SE3 keyframe_from_predicted,
                                             TrackingResult* result, bool feature_term) const {
  const SE3 prediction = keyframe_from_predicted;
  std::vector<FeatureCorrespondence> correspondences;
  const FrameFeatures& key = *keyframe_features_;
  if (!features.empty() && !key.empty()) {
    const std::vector<cv::DMatch> matches = MatchDescriptors(
        features.keypoints, features.descriptors, key.keypoints, key.descriptors, options_.match);
    std::vector<Eigen::Vector3d> source, target;
    std::vector<const cv::DMatch*> used;
    for (const cv::DMatch& m : matches) {
      const Eigen::Vector3d& p = features.points[m.queryIdx];
      const Eigen::Vector3d& q = key.points[m.trainIdx];
      if (!p.allFinite() || !q.allFinite()) continue;
      source.push_back(p);
      target.push_back(q);
      used.push_back(&m);
    }
    result->ransac = EstimateRigidRansac(source, target, options_.ransac);
    if (result->ransac.success) {
      for (int i : result->ransac.inlier_indices) {
        const cv::KeyPoint& k = key.keypoints[used[i]->trainIdx];
        correspondences.push_back({source[i], Eigen::Vector2d(k.pt.x, k.pt.y)});
      }
      const SE3 disagreement = prediction.Inverse() * result->ransac.target_from_source;
      if (disagreement.TranslationNorm() > options_.restart_m ||
          disagreement.RotationAngle() * 180.0 / M_PI > options_.restart_deg)
        keyframe_from_predicted = result->ransac.target_from_source;
    }
  }
  if (!feature_term) correspondences.clear();
  result->icp =
      AlignPointToPlane(reference, current, keyframe_from_predicted, options_.icp, correspondences);
  result->overlap = result->icp.valid_points ? static_cast<double>(result->icp.overlapping_points) /
                                                   result->icp.valid_points
                                             : 0.0;
  const SE3 correction = keyframe_from_predicted.Inverse() * result->icp.reference_from_current;
  const bool jumped = correction.TranslationNorm() > options_.max_jump_m ||
                      correction.RotationAngle() * 180.0 / M_PI > options_.max_jump_deg;
  return result->icp.success && !jumped;
}

void FrameToKeyframeTracker::MakeKeyframe(DepthPyramid current, FeaturesPtr features,
                                          const SE3& world_from_camera) {
  keyframe_ = std::move(current);
  keyframe_features_ = std::move(features);
  world_from_keyframe_ = world_from_camera;
  ++keyframes_;
}

TrackingResult FrameToKeyframeTracker::TrackWhileLost(const RgbdFrame& frame,
                                                      DepthPyramid current, FeaturesPtr features,
                                                      TrackingResult result) {
  // The last keyframe again, from the last good pose (a passing failure: blur, a covered lens),
  // held to the keyframe policy's overlap and feature support: after a loss the camera may be
  // anywhere, and a partial fit of a similar surface must not pass for the way back.
  const SE3 keyframe_from_last = world_from_keyframe_.Inverse() * world_from_previous_;
  const KeyframePolicy& policy = options_.keyframes;
  motion_known_ = false;  // the next frame's motion is not measured from this one
  if (AlignToKeyframe(keyframe_, current, *features, keyframe_from_last, &result) &&
      result.overlap >= policy.min_overlap &&
      (features->empty() || result.ransac.inliers >= policy.min_feature_inliers)) {
    result.status = TrackingStatus::kTracking;
    result.world_from_camera = world_from_keyframe_ * result.icp.reference_from_current;
    lost_frames_ = 0;
    velocity_ = SE3();
    world_from_previous_ = result.world_from_camera;
    if (NeedsKeyframe(frame, result)) {
      MakeKeyframe(std::move(current), std::move(features), result.world_from_camera);
      result.new_keyframe = true;
    }
    return result;
  }
  if (relocaliser_ != nullptr) {
    std::optional<Relocalisation> found = relocaliser_->Relocalise(frame, *features);
    if (found) {
      result.status = TrackingStatus::kRelocalised;
      result.world_from_camera = found->world_from_camera;
      result.relocalisation = std::move(found);
      lost_frames_ = 0;
      velocity_ = SE3();
      world_from_previous_ = result.world_from_camera;
      MakeKeyframe(std::move(current), std::move(features), result.world_from_camera);
      result.new_keyframe = true;
      return result;
    }
  }
  result.status = TrackingStatus::kLost;
  result.world_from_camera = world_from_previous_;
  if (relocaliser_ == nullptr || ++lost_frames_ > options_.relocalise_frames) {
    // Restart here, at the last good pose: the new keyframe's pose is a guess.
    result.status = TrackingStatus::kRestarted;
    lost_frames_ = 0;
    velocity_ = SE3();
    MakeKeyframe(std::move(current), std::move(features), world_from_previous_);
    result.new_keyframe = true;
  }
  return result;
}

void FrameToKeyframeTracker::RefineAgainstModel(const DepthPyramid& model,
                                                const DepthPyramid& current,
                                                TrackingResult* result) const {
  // The model has fused every earlier frame (less drift than one keyframe).
  const SE3 model_from_current = world_from_model_.Inverse() * result->world_from_camera;
  const IcpSummary refined = AlignPointToPlane(model, current, model_from_current, options_.icp);
  const SE3 step = model_from_current.Inverse() * refined.reference_from_current;
  if (refined.success && step.TranslationNorm() <= options_.max_jump_m &&
      step.RotationAngle() * 180.0 / M_PI <= options_.max_jump_deg) {
    result->world_from_camera = world_from_model_ * refined.reference_from_current;
    result->model_refined = true;
  }
}

bool FrameToKeyframeTracker::NeedsKeyframe(const RgbdFrame& frame,
                                           const TrackingResult& result) const {
  const KeyframePolicy& k = options_.keyframes;
  const SE3 keyframe_from_current = world_from_keyframe_.Inverse() * result.world_from_camera;
  const bool few_features = options_.use_features && !frame.color.empty() &&
                            result.ransac.inliers < k.min_feature_inliers;
  return keyframe_from_current.RotationAngle() * 180.0 / M_PI > k.max_rotation_deg ||
         keyframe_from_current.TranslationNorm() > k.max_translation_m ||
         result.overlap < k.min_overlap || few_features;
}

TrackingResult FrameToKeyframeTracker::Track(const RgbdFrame& input) {
  TrackingResult result;
  const DepthPyramid model = std::move(model_);  // for this frame only
  model_ = DepthPyramid();
  previous_time_ = std::exchange(frame_time_, input.timestamp);
  RgbdFrame frame = Undistorted(input);
  result.tracked_depth = frame.depth;
  // Rolling shutter: moved to its stamp with the last step's velocity before the one alignment.
  const bool rolling_shutter = options_.depth_readout_s > 0;
  const bool moved = rolling_shutter && initialized_ && lost_frames_ == 0 && motion_known_ &&
                     velocity_dt_ > 0;
  if (moved) MoveToStamp(input, velocity_, velocity_dt_, &frame, &result);
  DepthPyramid current = BuildDepthPyramid(frame.depth, pinhole_, options_.pyramid_levels);
  auto features = std::make_shared<const FrameFeatures>(
      options_.use_features ? ExtractFrameFeatures(frame, pinhole_, options_.surf)
                            : FrameFeatures());
  result.features = features;
  if (!initialized_) {
    initialized_ = true;
    motion_known_ = false;  // no step measured yet
    MakeKeyframe(std::move(current), std::move(features), SE3());
    world_from_previous_ = velocity_ = SE3();
    result.status = TrackingStatus::kInitialized;
    result.new_keyframe = true;
    result.overlap = 1.0;
    return result;
  }
  if (lost_frames_ > 0)
    return TrackWhileLost(frame, std::move(current), std::move(features), std::move(result));
  const SE3 predicted = world_from_previous_ * (options_.constant_velocity ? velocity_ : SE3());
  if (!AlignToKeyframe(keyframe_, current, *features, world_from_keyframe_.Inverse() * predicted,
                       &result, !moved)) {
    // Lost: this frame has no pose; the next ones look for it.
    lost_frames_ = 1;
    return TrackWhileLost(frame, std::move(current), std::move(features), std::move(result));
  }
  result.status = TrackingStatus::kTracking;
  if (rolling_shutter && !moved) RealignAtStamp(input, &frame, &current, &result);
  result.world_from_camera = world_from_keyframe_ * result.icp.reference_from_current;
  if (!model.depth.empty()) RefineAgainstModel(model, current, &result);
  const bool new_keyframe = NeedsKeyframe(frame, result);
  if (new_keyframe && options_.simulated_drift_deg_per_m != 0) {
    const SE3 step = world_from_keyframe_.Inverse() * result.world_from_camera;
    const double yaw = options_.simulated_drift_deg_per_m * step.TranslationNorm() * M_PI / 180;
    result.world_from_camera =
        result.world_from_camera *
        SE3(Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY())),
            Eigen::Vector3d::Zero());
  }
  velocity_ = world_from_previous_.Inverse() * result.world_from_camera;
  velocity_dt_ = frame_time_ - previous_time_;
  motion_known_ = true;
  world_from_previous_ = result.world_from_camera;
  if (new_keyframe) {
    MakeKeyframe(std::move(current), std::move(features), result.world_from_camera);
    result.new_keyframe = true;
  }
  return result;
}

void FrameToKeyframeTracker::MoveToStamp(const RgbdFrame& input, const SE3& step, double dt,
                                         RgbdFrame* frame, TrackingResult* result) const {
  // The translation only: the rotation of one step is too noisy a measure of the rotation
  // rate (with it, relative rotations over 12 frames of tum_fr1_xyz got worse: 0.62 -> 0.78
  // degrees median, against 0.50 without it).
  SE3::Tangent twist = step.Log() / dt;
  twist.tail<3>().setZero();
  result->depth_at_stamp = shutter_.DepthAtLastRow(input.depth, twist);
  frame->depth = UndistortedDepth(result->depth_at_stamp);
  result->tracked_depth = frame->depth;
}

void FrameToKeyframeTracker::RealignAtStamp(const RgbdFrame& input, RgbdFrame* frame,
                                            DepthPyramid* current, TrackingResult* result) const {
  const double dt = frame_time_ - previous_time_;
  if (dt <= 0) return;
  const SE3 keyframe_from_current = result->icp.reference_from_current;
  const SE3 step = world_from_previous_.Inverse() * world_from_keyframe_ * keyframe_from_current;
  TrackingResult moved_result;
  RgbdFrame moved = *frame;
  MoveToStamp(input, step, dt, &moved, &moved_result);
  DepthPyramid pyramid = BuildDepthPyramid(moved.depth, pinhole_, options_.pyramid_levels);
  const IcpSummary icp = AlignPointToPlane(keyframe_, pyramid, keyframe_from_current, options_.icp);
  if (!icp.success) return;
  result->icp = icp;
  result->depth_at_stamp = moved_result.depth_at_stamp;
  result->tracked_depth = moved.depth;
  *frame = std::move(moved);
  *current = std::move(pyramid);
}

}  // namespace gf
