// Rectified semi-global block matching (OpenCV's StereoSGBM) for a sideways keyframe pair, and the
// checks that keep it to pairs it can serve.
//
// RectifyForSgbm rectifies the pair (cv::stereoRectify, the pair's left camera first; a mostly
// vertical baseline is transposed into a horizontal one) and sizes the disparity search for the
// depth range keyframe 1 measures. The crop of cv::stereoRectify (alpha 0) magnifies the images
// (1.2-2.2 times on TUM's sideways pairs), which multiplies the pixels and disparities to search
// without adding detail: a crop magnified past max_zoom keeps its field of view on a smaller
// image. A pair whose baseline leans along the optical axis, or a mostly vertical one through
// TUM's lens distortion, was magnified 41 times (OpenCV then asked for 2843 disparities on a
// 480-pixel-wide image). Where the magnified search does not fit, the rectified focal length is
// first reduced, about the image centre, until it does. The pair is refused (and goes to the
// plane sweep) when the rectified views then keep too little of the images (min_valid_fraction)
// or no focal length fits. SGBM is never called with parameters OpenCV 4.6 cannot survive:
// minDisparity + numDisparities at or above the image width throws, segfaults or allocates a
// negative size inside StereoSGBM, past any catch (SgbmParametersFit).
//
// No threads, no I/O. Usage:
//   gf::SgbmRectification rect = gf::RectifyForSgbm(camera, key1_from_key2, 0.6, 3.6, {});
//   if (rect.usable) points = gf::SgbmPoints(rect, key1, key2, camera, {});  // left camera frame
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"

namespace gf {

struct SgbmOptions {
  int num_disparities = 128;   // most disparities SGBM searches (multiple of 16); the search
                               // itself follows keyframe 1's depth range
  double rectify_alpha = 0.0;  // cv::stereoRectify alpha: 0 crops to valid pixels (magnifies),
                               // 1 keeps all, -1 keeps the camera's focal length
  // Most magnification of the rectified images against the camera's own pixels (rectified focal
  // length / fx). A crop magnified more keeps its field of view on a smaller image: magnifying
  // past the camera's pixels adds no detail, only pixels and disparities to search (SGBM's time
  // grows with the magnification's cube). 0: the crop's own magnification, whatever it is. At
  // most the largest image side (a crop magnified more would be under a pixel).
  double max_zoom = 1.0;
  // Share of the rectified image that must show the scene in both views (inside the images and
  // the lens's field of view) for SGBM to run; below it the plane sweep fills the pair.
  double min_valid_fraction = 0.25;
  int block_size = 5;                 // SGBM block, pixels (odd)
  int uniqueness_ratio = 10;          // SGBM uniqueness, percent
  int speckle_window = 100;           // SGBM speckle filter window, pixels
  int speckle_range = 2;              // SGBM speckle range, disparity units
  double max_lr_difference_px = 1.0;  // left-right consistency, pixels (rounded: disp12MaxDiff)
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

// A pair rectified for SGBM, or why SGBM cannot serve it.
struct SgbmRectification {
  bool usable = false;
  std::string refusal;        // empty when usable, else "valid_region" or "disparity_range"
  std::string problem;        // one line with the figures, for the log
  bool swapped = false;       // keyframe 2 is the left camera (SGBM's reference image)
  bool vertical = false;      // epipolar lines run vertically: the images are transposed for SGBM
  bool rescaled = false;      // the crop's focal length was reduced so that the search fits
  double zoom = 0;            // rectified focal length / the camera's fx
  cv::Size size;              // rectified image (untransposed): the camera's, or smaller (max_zoom)
  double valid_fraction = 0;  // share of the rectified image that shows the scene in both views
  double fb = 0;              // rectified focal length * baseline: disparity = fb / depth
  int min_disparity = 0, num_disparities = 0;  // the SGBM search, pixels
  cv::Mat r_left, r_right, p_left, p_right;    // rectifying rotations and projections (R1 R2 P1 P2)
  std::string BriefReport() const;
};

// Rectifies the pair for SGBM over the disparities of depths [near_m, far_m] (keyframe 1).
SgbmRectification RectifyForSgbm(const Camera& camera, const SE3& key1_from_key2, double near_m,
                                 double far_m, const SgbmOptions& options);

// The pair's grey images rectified as `rect` says (SGBM's left image first; transposed when the
// epipolar lines run vertically), with masks (CV_8U, 255) of the pixels that show the scene.
struct RectifiedImages {
  cv::Mat left, right, valid_left, valid_right;
};
RectifiedImages RectifyImages(const SgbmRectification& rect, const RgbdFrame& key1,
                              const RgbdFrame& key2, const Camera& camera);

// True when OpenCV's StereoSGBM can run this search on a width x height image: a positive
// multiple of 16 disparities from min_disparity >= 0, ending by half the width (SGBM computes no
// disparity left of column min_disparity + num_disparities), and an odd block that fits.
bool SgbmParametersFit(int width, int height, int min_disparity, int num_disparities,
                       int block_size);

// Dense stereo points in the left camera's frame (SgbmRectification::swapped says which keyframe
// that is), after SGBM's left-right check; pixels whose block reaches outside either view's
// valid pixels are dropped. rect.usable must be true.
std::vector<Eigen::Vector3d> SgbmPoints(const SgbmRectification& rect, const RgbdFrame& key1,
                                        const RgbdFrame& key2, const Camera& camera,
                                        const SgbmOptions& options);

}  // namespace gf
