// The relative pose of two keyframes as stereo needs it, refined from their features and colour
// (registration for the stereo fill, fill/keyframe_pairs.h): keyframes with their U-SURF features
// and 3D points, the pose refinement (PnP on the matches, then dense photometric alignment) and
// its report.
//
// No threads, no I/O. Usage:
//   auto a = gf::MakeStereoKeyframe(0, frame_a, world_from_a, camera, surf_options);
//   auto b = gf::MakeStereoKeyframe(1, frame_b, world_from_b, camera, surf_options);
//   gf::PoseRefinement r = gf::RefinePairPose(*a, *b, camera, a_from_b_tracked, {}, {});
//   gf::AddPhotometricStep(*a, *b, camera, a_from_b_tracked, {}, &r);
#pragma once

#include <Eigen/Core>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"
#include "registration/ransac.h"
#include "registration/surf.h"

namespace gf {

// Refining the pair's relative pose before stereo. The tracker's chained keyframe poses are off by
// a centimetre or so over a few keyframes, which is 10% of a 10 cm baseline and so 10% of every
// stereo depth. The pair is re-estimated directly: key2's feature points (3D from its sensor
// depth) against their matches' pixels in key1, with lens distortion (cv::solvePnPRansac, then
// Levenberg-Marquardt on the inliers), then, optionally, by dense photometric alignment of the two
// undistorted images (OpenCV's RgbdOdometry), which is what the stereo needs: the pose under which
// the colour images agree. On TUM fr1/xyz with ground-truth poses as the start, the plane sweep's
// median error against the sensor fell from 10% (ground truth) to 2.8% (PnP) and 2.2% (PnP +
// photometric): the colour images, depth registration and motion-capture poses are not exactly
// consistent, and the stereo needs them consistent.
struct PoseRefinementOptions {
  double reprojection_px = 2.0;  // RANSAC inlier threshold, pixels
  int min_inliers = 30;          // fewer: keep the tracked pose
  double max_change_m = 0.05;    // larger change of the tracked pose: rejected, metres
  double max_change_deg = 5.0;   // ... degrees
  bool photometric = true;       // then dense photometric alignment
  // Its Gauss-Newton iterations per image-pyramid level, the full-size image first (each level
  // halves the size). The full-size level is skipped: it costs three quarters of the step (25 of
  // 32 ms a pair) and moves the pose by about half a millimetre (median, TUM fr1/xyz), below what
  // the fill and the map measure (docs/experiments/2026-12-07-faster-pairs-and-icp.md).
  std::vector<int> photometric_iterations = {0, 7, 7, 10};
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

// A keyframe as the stereo stage keeps it: the frame, its tracked pose, its SURF features.
struct StereoKeyframe {
  int id = 0;  // order of arrival
  RgbdFrame frame;
  SE3 world_from_camera;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  std::vector<Eigen::Vector3d> points;  // per keypoint, camera frame (lens distortion removed);
                                        // NaN where the sensor has no depth
};

// Computes the features (U-SURF on the grey image) and their 3D points. frame.color must be BGR.
std::shared_ptr<const StereoKeyframe> MakeStereoKeyframe(int id, const RgbdFrame& frame,
                                                         const SE3& world_from_camera,
                                                         const Camera& camera,
                                                         const SurfOptions& surf);

struct PoseRefinement {
  bool success = false;
  SE3 key1_from_key2;  // refined, or the initial pose when !success
  int matches = 0;     // matches with a 3D point in key2
  int inliers = 0;
  double rmse_px = 0;                   // reprojection RMSE of the inliers
  double change_m = 0, change_deg = 0;  // refined against initial
  std::string termination;
  std::string BriefReport() const;
};

PoseRefinement RefinePairPose(const StereoKeyframe& key1, const StereoKeyframe& key2,
                              const Camera& camera, const SE3& initial_key1_from_key2,
                              const MatchOptions& match, const PoseRefinementOptions& options);

// Dense photometric alignment after a successful feature refinement (OpenCV's RgbdOdometry on
// undistorted images, started from r->key1_from_key2): the stereo needs the pose under which
// key1's colour and key2's colour agree. Kept only within options' max_change of the feature
// pose; the change is then reported against `initial` (the tracked pose). Does nothing when
// r->success is false.
void AddPhotometricStep(const StereoKeyframe& key1, const StereoKeyframe& key2,
                        const Camera& camera, const SE3& initial,
                        const PoseRefinementOptions& options, PoseRefinement* r);

}  // namespace gf
