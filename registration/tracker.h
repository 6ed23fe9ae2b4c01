// Camera tracking: one interface, so frame-to-model tracking against the surfel map can replace
// the frame-to-keyframe tracker when the map lands.
//
// FrameToKeyframeTracker aligns each frame to the current keyframe with AlignPointToPlane, starting
// from a constant-velocity prediction. A frame becomes the new keyframe when it has moved more than
// the policy allows from the keyframe or shares too little of it. Tracking loss (ICP failure, too
// little overlap, an implausible jump) is reported in the result; the pose then stays at the last
// good one and the frame starts a new keyframe, so the run goes on.
//
// No threads, no I/O. Usage:
//   gf::FrameToKeyframeTracker tracker(camera, gf::TrackerOptions{});
//   for (each frame) { gf::TrackingResult r = tracker.Track(frame); trajectory.push_back(...); }
#pragma once

#include <string>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"
#include "registration/depth_pyramid.h"
#include "registration/icp.h"
#include "registration/ransac.h"
#include "registration/surf.h"

namespace gf {

struct KeyframePolicy {
  double max_rotation_deg = 5.0;    // new keyframe beyond this rotation from the keyframe
  double max_translation_m = 0.02;  // ... or this translation, metres
  double min_overlap = 0.7;         // ... or when fewer of the frame's points land on it
  int min_feature_inliers = 25;     // ... or when fewer features match it (features on)
  bool Check(std::string* message = nullptr) const;
};

struct TrackerOptions {
  int pyramid_levels = 3;  // must cover icp.iterations
  IcpOptions icp;
  // Sparse features (needs colour): SURF matches to the keyframe, 3D-3D RANSAC, and the RANSAC
  // inliers as the feature term of ICP's joint cost. RANSAC's pose replaces the constant-velocity
  // prediction when the two differ by more than restart_m / restart_deg.
  bool use_features = true;
  SurfOptions surf = [] {
    SurfOptions s;
    s.upright = true;  // a handheld camera barely rolls between frames: U-SURF, 40% faster
    s.max_features = 500;
    return s;
  }();
  MatchOptions match;
  RansacOptions ransac;
  double restart_m = 0.02;
  double restart_deg = 2.0;
  KeyframePolicy keyframes;
  bool constant_velocity = true;  // predict with the last inter-frame motion
  double max_jump_m = 0.15;       // larger correction of the prediction: treated as lost
  double max_jump_deg = 15.0;
  bool Check(std::string* message = nullptr) const;
};

enum class TrackingStatus { kInitialized, kTracking, kLost };
const char* TrackingStatusName(TrackingStatus status);

struct TrackingResult {
  bool model_refined = false;  // the pose was refined against the model (SetModelReference)
  TrackingStatus status = TrackingStatus::kInitialized;
  SE3 world_from_camera;
  bool new_keyframe = false;
  double overlap = 0;   // share of the frame's points that land on the keyframe's surface
  RansacReport ransac;  // feature alignment to the keyframe (empty when features are off)
  IcpSummary icp;
  std::string BriefReport() const;
};

class Tracker {
 public:
  virtual ~Tracker() = default;
  // frame.depth must match the tracker's camera.
  virtual TrackingResult Track(const RgbdFrame& frame) = 0;
};

class FrameToKeyframeTracker : public Tracker {
 public:
  // Throws std::logic_error when options.Check() fails (a programming error at this level).
  FrameToKeyframeTracker(const Camera& camera, const TrackerOptions& options);
  TrackingResult Track(const RgbdFrame& frame) override;
  int keyframes() const { return keyframes_; }
  // Frame-to-model tracking (KinectFusion, ElasticFusion): the next Track() first aligns the frame
  // to its keyframe as usual, then refines the pose by point-to-plane ICP against `depth`, the
  // model's depth rendered at world_from_reference (CV_32F metres on this camera's pixels, 0 =
  // none; the surfel map seen from the last pose). The refinement is kept only when ICP succeeds
  // on enough of the model and moves the pose by less than the jump limits. Keyframes (for the
  // stereo fill) are chosen as before.
  void SetModelReference(const cv::Mat& depth, const SE3& world_from_reference);

 private:
  // SURF keypoints of a frame with the 3D point under each (NaN where depth is missing).
  struct Features {
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    std::vector<Eigen::Vector3d> points;
  };
  Features ExtractFeatures(const RgbdFrame& frame) const;

  Camera camera_;
  TrackerOptions options_;
  bool initialized_ = false;
  DepthPyramid keyframe_;
  Features keyframe_features_;
  SE3 world_from_keyframe_;
  SE3 world_from_previous_;
  SE3 velocity_;  // previous_from_current of the last step
  int keyframes_ = 0;
  DepthPyramid model_;  // the model's depth at world_from_model_ (empty: none for the next frame)
  SE3 world_from_model_;
};

}  // namespace gf
