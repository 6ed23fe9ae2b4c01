// Filters on candidate depth before validation, for where window matching goes wrong: next to
// depth steps (foreground fattening) and on the rims of the holes stereo sees into (clear glass).
//
// Block matching spreads a textured surface's depth over the textureless pixels next to it: stereo
// depth within near_side_px of a farther depth (the near side of a step) or far_side_px of a nearer
// one is dropped (WithoutDepthSteps). Clear glass's rim is a colour edge at the glass's depth, and
// block matching spreads that depth over the background seen through the glass: inside a hole, a
// near depth beside a farther one. A hole that stereo sees into (its median stereo depth not
// nearer than its ring's sensor depth: no object stands out in front of what surrounds it) has
// its rim found (SeeThroughRim); there the same step rule runs over hole pixels only, with a wider
// window, and the plane sweep leaves the rim alone. A glossy or dark object stands in front of
// its ring and is not touched.
//
// No threads, no I/O.
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "acquisition/rgbd_frame.h"
#include "fill/fill_validation.h"

namespace gf {

struct DepthStepOptions {
  double jump = 0.05;    // relative depth step that counts as a discontinuity
  int far_side_px = 2;   // depth within this of a nearer depth (a step's far side) is dropped, px
  int near_side_px = 3;  // depth within this of a farther depth (its near side) is dropped, px
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

struct SeeThroughOptions {
  // A hole stereo sees into: its median stereo depth is at least (1 + ratio) times the median
  // sensor depth in its ring.
  double ratio = -0.03;
  int rim_px = 5;        // its rim: the hole pixels within this of a measured pixel (0: none), px
  int near_side_px = 8;  // on the rim, SGBM depth within this of a farther SGBM depth on another
                         // hole pixel is dropped, px
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

// A copy of `depth` (CV_32F, 0 = none) without the depths that have a farther one within
// near_side_px or a nearer one within far_side_px (steps over `jump`). Max/min filters over the
// window, so that a gap in the depth (pixels a left-right check dropped) does not hide a step.
cv::Mat WithoutDepthSteps(const cv::Mat& depth, int far_side_px, int near_side_px, double jump);

// Drops, in place, the hole pixels' depth that has a farther depth on another hole pixel within
// near_side_px (a step over `jump`), on the pixels where `where` (CV_8U) is non-zero.
void DropNearSideWithinHoles(const cv::Mat& hole_mask, int near_side_px, double jump,
                             const cv::Mat& where, cv::Mat* depth);

// The rims of the holes that stereo sees into: CV_8U, 255 on the hole pixels within rim_px of a
// measured pixel, in the holes whose median stereo depth (`stereo`, CV_32F on key1's pixels, 0 =
// none) is at least (1 + ratio) times the median sensor depth on the measured pixels within
// ring_px of them, both medians over min_samples or more. Holes that reach the image's edge are
// left out (the scene goes on out of view), and lines of hole pixels one or two pixels wide do not
// join holes. Empty when no hole qualifies.
cv::Mat SeeThroughRim(const RgbdFrame& key1, const cv::Mat& stereo,
                      const SeeThroughOptions& options, int ring_px, int min_samples);

// Keeps, in place, the rim pixels of the holes where a validated fill (fill_mask) filled at least
// min_filled pixels: where the depth did not pass validation, its view of the hole does not count.
void KeepRimsOfFilledHoles(const Holes& holes, const cv::Mat& fill_mask, int min_filled,
                           cv::Mat* rim);

}  // namespace gf
