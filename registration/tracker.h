// Camera tracking: one interface, so frame-to-model tracking against the surfel map can replace
// the frame-to-keyframe tracker when the map lands.
//
// FrameToKeyframeTracker aligns each frame to the current keyframe with AlignPointToPlane, starting
// from a constant-velocity prediction. A frame becomes the new keyframe when it has moved more than
// the policy allows from the keyframe or shares too little of it.
//
// Tracking loss (ICP failure, too little overlap, an implausible jump) is reported in the result,
// and the frame has no pose. Then each next frame is aligned to the last keyframe again, from the
// last good pose, and, when a Relocaliser is set (loop closure's keyframe database), looked up
// among all earlier keyframes; the first that verifies ends the loss (kRelocalised: the frame
// becomes a keyframe at the pose found). Frames until then are lost, not guessed. When nothing
// verifies for relocalise_frames frames (or at once, without a Relocaliser), tracking restarts:
// the frame becomes a keyframe at the last good pose (kRestarted: a guess, reported lost), and the
// run goes on from there.
//
// Tracking works on images undistorted onto the ideal pinhole camera of the same intrinsics
// (pinhole_camera()): depth by nearest pixel, colour bilinear. Lens distortion ignored would bend
// the geometry by up to a few per cent at the image's edges (TUM fr1's k1 is 0.26); between
// neighbouring frames that nearly cancels, but not between views far apart (loops).
//
// No threads, no I/O. Usage:
//   gf::FrameToKeyframeTracker tracker(camera, gf::TrackerOptions{});
//   for (each frame) { gf::TrackingResult r = tracker.Track(frame); trajectory.push_back(...); }
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"
#include "registration/depth_pyramid.h"
#include "registration/frame_features.h"
#include "registration/icp.h"
#include "registration/ransac.h"
#include "registration/rolling_shutter.h"
#include "registration/surf.h"

namespace gf {

// When a frame becomes a keyframe. A keyframe is tracked against, filled by stereo, searched for
// loops and stored: each costs the fill and the loop search (about 0.35 s of CPU on a 2-core
// machine). 2 cm of travel is about 9 px of parallax at the 1.2 m of a desk scene (f = 525 px).
struct KeyframePolicy {
  double max_rotation_deg = 5.0;    // new keyframe beyond this rotation from the keyframe
  double max_translation_m = 0.02;  // ... or this translation, metres
  double min_overlap = 0.7;         // ... or when fewer of the frame's points land on it
  int min_feature_inliers = 25;     // ... or when fewer features match it (features on)
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
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
  // Time from the exposure of the depth image's first row to its last, seconds (0: a global
  // shutter, as synthetic data and time-of-flight cameras have). The Kinect v1's depth comes from
  // a rolling-shutter infrared sensor read out over the frame period: 1/30 s at 30 frames/s
  // (rolling_shutter.h). With it, the camera's velocity over the last tracked step moves each
  // frame's points to its stamp's instant before the frame is aligned, and its pose is the
  // camera's at the stamp (where no step is known yet, the frame is aligned as the sensor gave it,
  // moved with the step that measured and aligned again).
  double depth_readout_s = 1.0 / 30.0;
  // The order of the readout's lines (rolling_shutter.h): camera.json's depth_readout_order.
  ReadoutOrder depth_readout_order = ReadoutOrder::kTopToBottom;
  double max_jump_m = 0.15;       // larger correction of the prediction: treated as lost
  double max_jump_deg = 15.0;
  // After a loss, frames looked up among earlier keyframes (with a Relocaliser) before tracking
  // restarts at the last good pose.
  int relocalise_frames = 30;
  // For evaluation only (0 in real use): a yaw about the camera's y axis, in degrees per metre
  // travelled, added to each new keyframe's pose: simulated drift, to measure how much of it loop
  // closure removes.
  double simulated_drift_deg_per_m = 0.0;
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

enum class TrackingStatus {
  kInitialized,   // the first frame: the world frame
  kTracking,      // aligned to its keyframe
  kLost,          // no pose: alignment failed, or the run is still lost
  kRelocalised,   // found again against an earlier keyframe; a new keyframe
  kRestarted,     // lost too long: a new keyframe at the last good pose (a guess, no pose)
};
const char* TrackingStatusName(TrackingStatus status);

// Where a lost frame was found again (Relocaliser).
struct Relocalisation {
  int keyframe = -1;         // the earlier keyframe (loop closure's id) it was aligned to
  SE3 keyframe_from_camera;  // the alignment
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();  // of it
  SE3 world_from_camera;     // in the tracker's world frame
};

// Finds a lost frame among earlier keyframes. Called from the tracking thread; implementations
// guard what they share with other threads.
class Relocaliser {
 public:
  virtual ~Relocaliser() = default;
  virtual std::optional<Relocalisation> Relocalise(const RgbdFrame& frame,
                                                   const FrameFeatures& features) = 0;
};

struct TrackingResult {
  bool model_refined = false;  // the pose was refined against the model (SetModelReference)
  TrackingStatus status = TrackingStatus::kInitialized;
  // kInitialized, kTracking, kRelocalised; lost frames carry the last good pose, not theirs.
  bool has_pose() const {
    return status != TrackingStatus::kLost && status != TrackingStatus::kRestarted;
  }
  SE3 world_from_camera;
  bool new_keyframe = false;
  double overlap = 0;   // share of the frame's points that land on the keyframe's surface
  RansacReport ransac;  // feature alignment to the keyframe (empty when features are off)
  IcpSummary icp;               // alignment to the keyframe
  cv::Mat tracked_depth;        // the frame's depth as tracking used it (on pinhole_camera())
  // The frame's depth moved to its stamp's instant (depth_readout_s), on the input camera's
  // pixels: what the pose places in the world. Empty when the frame was not moved.
  cv::Mat depth_at_stamp;
  std::shared_ptr<const FrameFeatures> features;  // the frame's (empty without colour)
  std::optional<Relocalisation> relocalisation;   // kRelocalised only
  std::string BriefReport() const;
};

// The options with the sensor's own depth readout (time, order) where its camera.json gives it.
TrackerOptions ForSensor(TrackerOptions options, const CameraFile& camera);

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
  // The camera of the images tracking works on: the input camera without lens distortion.
  const Camera& pinhole_camera() const { return pinhole_; }
  // Frame-to-model tracking (KinectFusion, ElasticFusion): the next Track() first aligns the frame
  // to its keyframe as usual, then refines the pose by point-to-plane ICP against `depth`, the
  // model's depth rendered at world_from_reference (CV_32F metres on this camera's pixels, 0 =
  // none; the surfel map seen from the last pose). The refinement is kept only when ICP succeeds
  // on enough of the model and moves the pose by less than the jump limits. Keyframes (for the
  // stereo fill) are chosen as before.
  void SetModelReference(const cv::Mat& depth, const SE3& world_from_reference);
  // Looks lost frames up among earlier keyframes (may be null: restart at once). Not owned.
  void SetRelocaliser(Relocaliser* relocaliser) { relocaliser_ = relocaliser; }

 private:
  using FeaturesPtr = std::shared_ptr<const FrameFeatures>;
  // Aligns the frame to the keyframe from keyframe_from_predicted (features re-seed it when the
  // prediction is off); fills result->ransac, icp, overlap. True when ICP succeeded without an
  // implausible jump from the prediction. feature_term: the feature matches also enter ICP's
  // cost; off for depth moved to its stamp, whose colour (read out by its own rolling shutter)
  // the move does not correct.
  bool AlignToKeyframe(const DepthPyramid& reference, const DepthPyramid& current,
                       const FrameFeatures& features, SE3 keyframe_from_predicted,
                       TrackingResult* result, bool feature_term = true) const;
  // Rolling shutter (depth_readout_s): the frame's depth (`frame`: the input undistorted) moved
  // to its stamp's instant by a camera moving `step` (previous_from_current) in `dt` seconds;
  // sets result->depth_at_stamp and tracked_depth. A tracked frame is moved with the last step's
  // velocity before its one alignment.
  void MoveToStamp(const RgbdFrame& input, const SE3& step, double dt, RgbdFrame* frame,
                   TrackingResult* result) const;
  // Where that velocity is not known (the frame after the first, after a loss): the frame,
  // aligned as the sensor gave it, moved with the step that alignment measured and aligned again
  // from there. Replaces *frame, *current, result->icp and the depths when that succeeds.
  void RealignAtStamp(const RgbdFrame& input, RgbdFrame* frame, DepthPyramid* current,
                      TrackingResult* result) const;
  // The frame becomes the keyframe at world_from_camera.
  void MakeKeyframe(DepthPyramid current, FeaturesPtr features, const SE3& world_from_camera);
  TrackingResult TrackWhileLost(const RgbdFrame& frame, DepthPyramid current,
                                FeaturesPtr features, TrackingResult result);
  void RefineAgainstModel(const DepthPyramid& model, const DepthPyramid& current,
                          TrackingResult* result) const;
  bool NeedsKeyframe(const RgbdFrame& frame, const TrackingResult& result) const;

  // The frame's depth, colour and hole mask on the pinhole camera (the frame itself without
  // distortion).
  RgbdFrame Undistorted(const RgbdFrame& frame) const;
  cv::Mat UndistortedDepth(const cv::Mat& depth) const;

  Camera camera_;
  Camera pinhole_;                   // camera_ without distortion
  RollingShutter shutter_;           // the depth sensor's, on camera_
  cv::Mat undistort_x_, undistort_y_;  // cv::remap maps (empty: no distortion)
  TrackerOptions options_;
  Relocaliser* relocaliser_ = nullptr;
  bool initialized_ = false;
  int lost_frames_ = 0;  // frames since tracking was lost (0: tracking)
  DepthPyramid keyframe_;
  FeaturesPtr keyframe_features_;
  SE3 world_from_keyframe_;
  SE3 world_from_previous_;
  SE3 velocity_;            // previous_from_current of the last tracked step
  double velocity_dt_ = 0;  // ... and its seconds
  double previous_time_ = 0, frame_time_ = 0;  // the last frame's stamp, this frame's
  // velocity_ was measured by the last two frames' alignments (not after a loss or at the start).
  bool motion_known_ = false;
  int keyframes_ = 0;
  DepthPyramid model_;  // the model's depth at world_from_model_ (empty: none for the next frame)
  SE3 world_from_model_;
};

}  // namespace gf
