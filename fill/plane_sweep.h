// Plane-sweep stereo for the pixels of a keyframe that rectified stereo cannot serve: pairs whose
// motion is mostly forward (the epipole inside the image), where cv::stereoRectify degenerates,
// and holes SGBM left empty (image borders, weak texture).
//
// Fronto-parallel planes of keyframe 1, evenly spaced in inverse depth, are swept through the
// requested depth range; for each plane the other views are warped into keyframe 1 by the plane's
// homography (on undistorted images shrunk by `downscale`) and compared with keyframe 1 by
// zero-mean normalised cross-correlation over a window (window sums per row, fused with the warp in
// loops that vectorise; windows weighted by keyframe 1's coverage, so they may cross its border;
// a hole pixel's window uses hole pixels only, so a measured surface's texture next to the hole
// does not carry its depth into it).
// The cost 1 - mean NCC over the views that see a pixel is aggregated along 8 image paths
// (semi-global matching); each pixel takes the plane of least aggregated cost, refined to sub-plane
// precision by a parabola. A pixel gets a depth only when its window has texture, the correlation
// at that plane is high enough, the minimum is distinct (below every plane more than one step away
// by a margin) and the views that see it give enough parallax (a 3% change of depth moves the pixel
// by at least min_parallax_px in some view: near the epipole forward motion gives none).
//
// No threads, no I/O. Usage:
//   gf::PlaneSweepResult r = gf::SweepDepth(key1, {{&key2, key1_from_key2}}, camera, mask,
//                                           0.5, 3.0, {});
//   // r.depth: CV_32F metres in keyframe 1's (distorted) image, 0 where no depth was accepted
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"

namespace gf {

struct PlaneSweepOptions {
  int window_px = 7;               // correlation window side, pixels (odd)
  int max_planes = 80;             // most planes swept (time per pair grows with them)
  double max_step_px = 1.0;        // the plane spacing moves no pixel by more than this, pixels
  double min_ncc = 0.5;            // textured pixels: mean correlation needed at the chosen plane
  double min_uniqueness = 0.05;    // chosen plane's (aggregated) cost must be this much (relative)
                                   // below every plane more than one step away
  double min_parallax_px = 0.15;   // a 3% depth change must move the pixel this much in a view, px
  double min_texture = 0.5;        // grey-level standard deviation of keyframe 1's window
  double min_window_inside = 0.3;  // fraction of the window inside keyframe 1's image (borders)
  // Semi-global aggregation of the matching cost (cost 1 - NCC, in hundredths) along 8 image
  // paths, as in Hirschmueller's SGM: neighbours on a path pay smooth_small for a change of one
  // plane and smooth_large for a bigger jump. Lets depth reach weakly textured pixels from their
  // textured surroundings; 0 for both turns it off (winner-takes-all per pixel).
  int smooth_small = 4;
  int smooth_large = 40;
  int downscale = 2;          // sweep on images shrunk by this factor (1: full size)
  int textureless_cost = 30;  // cost of every plane where keyframe 1's window has no texture
  // How far beyond the wanted pixels and their validation ring matching costs are computed,
  // pixels of keyframe 1's image (about one correlation window, window_px * downscale): the
  // evidence that aggregation carries into a wanted pixel comes from within this distance; beyond
  // it every plane costs textureless_cost without matching (aggregation still crosses it).
  int context_px = 16;
  // Windows of hole pixels use hole pixels only (where they fill min_window_inside of the
  // window): a measured surface's texture then cannot carry its depth into the hole next to it
  // (foreground fattening, e.g. a label's depth onto the clear glass below it). Projector-shadow
  // pixels do not count as hole pixels here (they show the background beside an edge).
  bool hole_windows = true;
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

struct SweepView {
  const RgbdFrame* frame = nullptr;
  SE3 key1_from_view;
};

struct PlaneSweepResult {
  cv::Mat depth;  // CV_32F metres, keyframe 1's image; 0 = none
  cv::Mat score;  // CV_32F best mean correlation where depth > 0
  int planes = 0;
  int requested_pixels = 0;
  int accepted_pixels = 0;
  std::string BriefReport() const;
};

// mask: CV_8U, non-zero where depth is wanted (keyframe 1's image). Depths in [min_depth_m,
// max_depth_m]. Views must have BGR colour.
PlaneSweepResult SweepDepth(const RgbdFrame& key1, const std::vector<SweepView>& views,
                            const Camera& camera, const cv::Mat& mask, double min_depth_m,
                            double max_depth_m, const PlaneSweepOptions& options);

}  // namespace gf
