// SURF: Speeded-Up Robust Features (H. Bay, A. Ess, T. Tuytelaars, L. Van Gool, "SURF: Speeded Up
// Robust Features", CVIU 110(3), 2008), implemented here because Debian's OpenCV has no
// xfeatures2d.
//
//  - Integral image; Fast-Hessian detector: box-filter approximations of the second derivatives
//    Dxx, Dyy, Dxy at filter sizes 9, 15, 21, 27 (octave 1), doubling the step per octave;
//    det(H) = Dxx Dyy - (0.9 Dxy)^2 normalised by the filter area.
//  - Maxima of det(H) over 3x3x3 neighbourhoods in (x, y, scale), refined to sub-pixel and
//    sub-scale by a quadratic fit; scale s = 1.2 * L / 9 for filter size L.
//  - Orientation: Haar wavelet responses (size 4s) in a circle of radius 6s, Gaussian weighted
//    (sigma 2s), summed in a sliding pi/3 window; the longest sum gives the angle. Upright SURF
//    (U-SURF) skips it.
//  - Descriptor: a 20s square aligned with the orientation, 4x4 subregions of 5x5 samples of Haar
//    responses (size 2s) in the rotated frame, Gaussian weighted (sigma 3.3s); per subregion
//    sum dx, sum dy, sum |dx|, sum |dy|: 64 floats, normalised to unit length.
// The Laplacian sign (trace of H) is kept with each keypoint to speed matching.
//
// No threads, no I/O. Usage:
//   gf::SurfOptions options;                       // options.upright = true for U-SURF
//   gf::SurfFeatures f = gf::DetectAndDescribeSurf(gray, options);
//   // f.keypoints[i] (OpenCV KeyPoint: pt, size = 2 * 10s... see below), f.descriptors row i
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace gf {

struct SurfOptions {
  // On det(H) of an image scaled to [0, 1], which stays below 1 (box-filter second derivatives
  // normalised by the filter area are at most 2/3): at most 1.
  double hessian_threshold = 0.0004;
  int octaves = 4;                    // octaves of the scale space
  int initial_step = 2;               // sampling step of the first octave, pixels (1 = every pixel)
  bool upright = false;               // U-SURF: no orientation (faster, not rotation invariant)
  int max_features = 1500;            // keep the strongest; 0 = all
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

struct SurfFeatures {
  // pt: position (pixels); size: 20 s (the descriptor window, as OpenCV reports SURF sizes);
  // angle: degrees in [0, 360), -1 for upright; response: det(H); class_id: Laplacian sign (+1/-1).
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;  // CV_32F, one 64-float row per keypoint
};

// gray: CV_8UC1. Keypoints sorted by decreasing response.
SurfFeatures DetectAndDescribeSurf(const cv::Mat& gray, const SurfOptions& options);

}  // namespace gf
