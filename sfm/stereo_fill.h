// Filling a keyframe's depth holes by dense stereo with a second keyframe whose relative pose the
// tracker knows (the heart of GlassFusion: glass, shiny and dark surfaces that the Kinect cannot
// measure are still textured in colour).
//
// Steps: check the pair (baseline, epipole outside the image: forward motion gives no usable
// stereo), rectify both colour images (cv::stereoRectify) with the pair's left camera first
// (a mostly vertical baseline is transposed into a horizontal one), compute disparity with
// cv::StereoSGBM in both directions (the right view's by mirroring the images) and keep pixels
// that agree (left-right check), convert to metric depth in the left camera, move it into
// keyframe 1 with the known pose and project it into keyframe 1's image (z-buffer), then validate:
// the stereo depth must agree with the Kinect on measured pixels around each hole, or that hole is
// left empty. Only pixels the sensor left empty are filled; measured pixels are never changed.
//
// No threads, no I/O. Usage:
//   gf::StereoFillResult r = gf::FillHolesByStereo(key1, key2, camera, key1_from_key2, {});
//   if (r.success) depth = r.filled_depth;   // r.fill_mask says which pixels are new
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"

namespace gf {

struct StereoFillOptions {
  double min_baseline_m = 0.04;       // shorter baselines give too little parallax, metres
  int num_disparities = 128;          // SGBM search range, pixels (multiple of 16)
  int block_size = 5;                 // SGBM block, pixels (odd)
  int uniqueness_ratio = 10;          // SGBM uniqueness, percent
  int speckle_window = 100;           // SGBM speckle filter window, pixels
  int speckle_range = 2;              // SGBM speckle range, disparity units
  double max_lr_difference_px = 1.0;  // left-right consistency, pixels
  double min_depth_m = 0.3;           // filled depths outside this range are dropped, metres
  double max_depth_m = 6.0;
  int ring_px = 6;               // validation ring around each hole, pixels
  int min_ring_samples = 15;     // holes with fewer stereo/Kinect pairs in the ring stay empty
  double max_ring_error = 0.03;  // median relative error allowed in the ring
  double max_pair_error = 0.05;  // median relative error over the whole image: else reject
  int edge_margin_px = 2;        // drop stereo depth this close to a depth discontinuity
  double edge_jump = 0.05;       // relative depth step that counts as a discontinuity
  bool Check(std::string* message = nullptr) const;
};

struct StereoFillResult {
  bool success = false;
  std::string termination;  // "ok" or why the pair was not used
  cv::Mat stereo_depth;     // CV_32F metres in keyframe 1's image, 0 = none (all stereo)
  cv::Mat filled_depth;     // CV_32F: the sensor's depth plus the filled pixels
  cv::Mat fill_mask;        // CV_8U: 255 where a hole was filled
  int hole_pixels = 0;      // pixels the sensor left empty
  int filled_pixels = 0;
  double stereo_error_median = 0;  // relative, stereo vs Kinect where both exist
  std::string BriefReport() const;
};

// key1/key2: colour (BGR) and metric depth with hole masks; key1_from_key2 maps points from
// keyframe 2's camera into keyframe 1's. Both frames use `camera`.
StereoFillResult FillHolesByStereo(const RgbdFrame& key1, const RgbdFrame& key2,
                                   const Camera& camera, const SE3& key1_from_key2,
                                   const StereoFillOptions& options);

}  // namespace gf
