// The ways GlassFusion finds depth for a keyframe's holes from other views, behind one small
// interface (as Open3D's TransformationEstimation puts its ICP variants): each computes a
// candidate depth image for keyframe 1, which the filters (depth_filters.h) and the validation
// against the sensor (fill_validation.h) then judge the same way, whatever made it.
//
//  - RectifiedSgbmCandidates: OpenCV's SGBM on the rectified pair (rectified_sgbm.h), the points
//    moved into keyframe 1 and projected into its image, nearest surface first;
//  - PlaneSweepCandidates: the multi-view plane sweep (plane_sweep.h) with the partner and the
//    third view, for forward pairs and the holes SGBM left empty;
//  - DepthMapCandidates: a depth map already on keyframe 1's pixels (COLMAP's patch_match_stereo).
//
// No threads, no I/O. Usage:
//   const gf::StereoPair pair{key1, key2, camera, key1_from_key2, third, 0.6, 3.6};
//   cv::Mat depth = gf::PlaneSweepCandidates(options).Compute(pair, hole_region);
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"
#include "fill/fill_validation.h"
#include "fill/plane_sweep.h"
#include "fill/rectified_sgbm.h"

namespace gf {

// What every method sees: the pair, its relative pose, the third view and the depth range to
// search (keyframe 1's measured range, metres).
struct StereoPair {
  const RgbdFrame& key1;
  const RgbdFrame& key2;
  const Camera& camera;
  SE3 key1_from_key2;
  ThirdView third;
  double near_m = 0, far_m = 0;
};

class DepthCandidates {
 public:
  virtual ~DepthCandidates() = default;
  virtual std::string Name() const = 0;
  // Candidate depth on keyframe 1's pixels (CV_32F metres, 0 = none), wanted where `region`
  // (CV_8U) is non-zero, or everywhere when it is empty.
  virtual cv::Mat Compute(const StereoPair& pair, const cv::Mat& region) const = 0;
};

class RectifiedSgbmCandidates : public DepthCandidates {
 public:
  // rect must be usable (RectifyForSgbm); depths outside [min_depth_m, max_depth_m] are dropped.
  RectifiedSgbmCandidates(SgbmRectification rect, const SgbmOptions& options, double min_depth_m,
                          double max_depth_m);
  std::string Name() const override { return "rectified SGBM"; }
  cv::Mat Compute(const StereoPair& pair, const cv::Mat& region) const override;

 private:
  SgbmRectification rect_;
  SgbmOptions options_;
  double min_depth_m_, max_depth_m_;
};

class PlaneSweepCandidates : public DepthCandidates {
 public:
  explicit PlaneSweepCandidates(const PlaneSweepOptions& options) : options_(options) {}
  std::string Name() const override { return "plane sweep"; }
  cv::Mat Compute(const StereoPair& pair, const cv::Mat& region) const override;

 private:
  PlaneSweepOptions options_;
};

class DepthMapCandidates : public DepthCandidates {
 public:
  // depth: CV_32F metres on keyframe 1's pixels, 0 = none.
  DepthMapCandidates(cv::Mat depth, std::string name) : depth_(depth), name_(std::move(name)) {}
  std::string Name() const override { return name_; }
  cv::Mat Compute(const StereoPair& pair, const cv::Mat& region) const override;

 private:
  cv::Mat depth_;
  std::string name_;
};

}  // namespace gf
