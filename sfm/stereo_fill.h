// Filling a keyframe's depth holes by dense stereo with a second keyframe whose relative pose the
// tracker knows (the heart of GlassFusion: glass, shiny and dark surfaces that the Kinect cannot
// measure are still textured in colour).
//
// Steps: check the pair (baseline; epipole inside the image, i.e. mostly forward motion, goes to
// the plane sweep of sfm/plane_sweep.h over the holes instead, with the third view when given;
// after SGBM, the sweep also covers the holes SGBM found no depth for, validated separately,
// except the rims of the holes SGBM sees into, clear glass's above all),
// rectify sideways pairs and match them with SGBM over the disparities of keyframe 1's measured
// depth range (sfm/rectified_sgbm.h; a pair whose rectification is degenerate goes to the plane
// sweep instead, and StereoFillResult::path says so), move the depth into keyframe 1 with the
// known pose and project it into keyframe 1's image (z-buffer), then validate: the stereo depth must agree with the Kinect on measured pixels around
// each hole, or that hole is left empty. In a projector shadow the depth must lie nearer the
// shadow's far side than its near one (the shadow is the far surface). Where a third keyframe sees
// the filled point, its colour there must match keyframe 1's (normalised cross-correlation of
// patches, over hole pixels only for a hole pixel), unless the third keyframe's sensor shows the
// point hidden behind a nearer surface. Only pixels the sensor left empty are filled; measured
// pixels are never changed. Each filled pixel carries a confidence and a source tag.
//
// No threads, no I/O. Usage:
//   gf::StereoFillResult r = gf::FillHolesByStereo(key1, key2, camera, key1_from_key2, {});
//   if (r.success) depth = r.filled_depth;   // r.fill_mask says which pixels are new
//   // with a third keyframe for the photometric check:
//   r = gf::FillHolesByStereo(key1, key2, camera, key1_from_key2, {}, {&key3, key1_from_key3});
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"
#include "sfm/plane_sweep.h"
#include "sfm/rectified_sgbm.h"

namespace gf {

struct StereoFillOptions {
  double min_baseline_m = 0.04;     // shorter baselines give too little parallax, metres
  double epipole_margin_px = 40;    // epipole this close to the image (or inside): forward motion
  bool plane_sweep_forward = true;  // forward motion: plane sweep (else the pair is skipped)
  bool plane_sweep_always = false;  // plane sweep for sideways pairs too (instead of SGBM)
  bool plane_sweep_after_sgbm = true;  // sideways pairs: plane-sweep the holes SGBM found no
                                       // depth for
  // ... and the holes whose SGBM depth the edge margins or validation dropped (off: on the demo
  // scene, clear glass filled at the glass's depth 204 -> 43 pixels with true poses; synthetic
  // good fill 74.1 -> 71.9%, ICL and TUM unchanged)
  bool sweep_sgbm_rejects = false;
  bool sweep_shadows = false;  // plane-sweep projector-shadow holes too
  PlaneSweepOptions plane_sweep;
  SgbmOptions sgbm;          // rectified SGBM of sideways pairs (sfm/rectified_sgbm.h)
  double min_depth_m = 0.3;  // filled depths outside this range are dropped, metres
  double max_depth_m = 6.0;
  int ring_px = 6;                    // validation ring around each hole, pixels
  int min_ring_samples = 15;          // holes with fewer stereo/Kinect pairs in the ring stay empty
  int ring_cell_px = 40;              // large holes are judged piecewise, by the ring in each cell
                                      // of this size (0: whole holes only)
  double max_ring_error = 0.03;       // median relative error allowed in the ring
  bool ring_scale_correction = true;  // scale each hole's stereo by its ring's sensor/stereo ratio
  double max_ring_scale = 0.10;       // ... when that ratio is within 1 +- this
  double max_pair_error = 0.08;       // median relative error over the whole image: else reject
  // Stereo depth next to a depth step is dropped: within edge_margin_px of a nearer stereo depth
  // (the step's far side) and within edge_margin_near_px of a farther one (its near side, which
  // block matching spreads: foreground fattening). Pixels.
  int edge_margin_px = 2;
  int edge_margin_near_px = 3;
  double edge_jump = 0.05;  // relative depth step that counts as a discontinuity
  // SGBM's depth on a hole pixel with a farther SGBM depth on another hole pixel within this many
  // pixels is dropped too (0: off): clear glass's rim is matched at the glass's depth, which
  // spreads over the background seen through it, while a glossy or dark object's border meets
  // the measured background outside its hole. 4 px: clear glass at the glass's depth on the demo
  // 82 -> 32 pixels, synthetic seed 5 fill 86.4 -> 85.8%; 5 px: 24, 84.4%. Not for the sweep's
  // depth (no gain: 82 -> 81).
  int hole_edge_margin_near_px = 4;
  // A hole that SGBM sees into: its median SGBM depth is at least (1 + see_through_ratio) times
  // the median sensor depth in its ring, so no object stands out in front of what surrounds it:
  // clear glass with the background behind it (or a patch of a surface). Its rim, the pixels
  // within see_through_rim_px of its border (0: off), is where both window matchers take the
  // depth of the glass's edge or of a label on it; there only SGBM's depth fills, and only
  // without a farther SGBM depth on a hole pixel within see_through_margin_px (instead of
  // hole_edge_margin_near_px) and without a sensor depth more than see_through_sensor_step
  // farther within see_through_sensor_px (0: no such test): the background measured beside the
  // glass; the sweep leaves the rim alone once SGBM's validated depth fills that hole. A glossy or
  // dark object stands in front of its ring and is not touched; holes that reach the image's edge
  // are left out, and lines of hole pixels one or two wide do not join holes (SeeThroughRim).
  // Demo: clear glass at the glass's depth 31 -> 0 pixels, clear-glass fill 77.7 -> 73.0%; shelf
  // scene, seeds 1-5: 49-121 -> 0, fill 70.4 -> 69.0% (seed 1); ICL and punched TUM unchanged.
  double see_through_ratio = -0.03;
  int see_through_rim_px = 5;
  int see_through_margin_px = 8;
  int see_through_sensor_px = 3;
  double see_through_sensor_step = 0.03;
  // Photometric check in a third keyframe (when one is given). A hole pixel's patch uses keyframe
  // 1's hole pixels only (photometric_hole_patches), so that a measured surface beside the hole
  // (a label above clear glass) cannot make it match at that surface's depth. Patch 7 -> 15 with
  // hole patches: good fills on punched TUM 0:150 51.7% -> 54.5%, clear glass at the glass's
  // depth on the demo scene 414 -> 204 pixels.
  int photometric_patch_px = 15;  // patch side for the comparison, pixels (odd)
  bool photometric_hole_patches = true;
  double min_ncc = 0.5;        // textured patches must correlate at least this much
  double min_patch_std = 4.0;  // below this grey-level spread a patch counts as textureless ...
  double max_mean_difference = 25.0;  // ... and then only the mean grey levels are compared
  double occlusion_margin = 0.05;     // third view's sensor nearer by this (relative): hidden there
  bool Check(std::string* message = nullptr) const;
};


// Optional third keyframe for the photometric check.
struct ThirdView {
  const RgbdFrame* frame = nullptr;  // null: no check
  SE3 key1_from_key3;
};

struct StereoFillResult {
  bool success = false;
  std::string termination;  // "ok" or why the pair was not used
  std::string method;       // "rectified SGBM", "plane sweep", "rectified SGBM + plane sweep"
  // How the pair was served, as report.json counts pairs: "rectified_sgbm", "plane_sweep_forward"
  // (epipole in an image), "plane_sweep_degenerate_rectification" (sgbm_refused says why),
  // "plane_sweep_requested" (plane_sweep_always), or "none" (the pair was not used).
  std::string path = "none";
  std::string sgbm_refused;         // SgbmRectification::refusal for degenerate sideways pairs
  SgbmRectification rectification;  // of sideways pairs (BriefReport() for the log)
  cv::Mat stereo_depth;             // CV_32F metres in keyframe 1's image, 0 = none (all stereo)
  cv::Mat filled_depth;             // CV_32F: the sensor's depth plus the filled pixels
  cv::Mat fill_mask;                // CV_8U: 255 where a hole was filled
  cv::Mat source;                   // CV_8U: DepthSource per pixel of filled_depth
  cv::Mat confidence;   // CV_32F in [0, 1]: 1 on sensor pixels, the fill's confidence on filled
                        // ones (ring agreement times photometric agreement), 0 elsewhere
  int hole_pixels = 0;  // pixels the sensor left empty
  int filled_pixels = 0;
  int rejected_by_ring = 0;        // hole pixels with stereo depth whose hole failed the ring test
  int rejected_by_photometry = 0;  // ... that the third view contradicted
  int rejected_by_shadow = 0;      // ... in projector shadows, nearer the shadow's near side
  bool third_view_used = false;
  double stereo_error_median = 0;    // relative, stereo vs Kinect where both exist
  double stereo_error_median_m = 0;  // the same in metres
  std::string BriefReport() const;
};

// True when the epipole of camera b in camera a's image (the direction of the baseline, forward or
// backward) lies inside the image or within margin_px of it: rectification then degenerates and
// block matching finds no usable disparity. Checks a's image only; call it both ways round.
bool EpipoleInsideImage(const Camera& camera, const SE3& a_from_b, double margin_px);

// A forward pair: the epipole lies inside (or within margin_px of) either keyframe's image, so
// rectified stereo cannot serve it (EpipoleInsideImage both ways round).
bool IsForwardPair(const Camera& camera, const SE3& key1_from_key2, double margin_px);

// The rims of the holes that stereo sees into, as FillHolesByStereo finds them
// (StereoFillOptions::see_through_ratio): CV_8U, 255 on the hole pixels within see_through_rim_px
// of a measured pixel, in the holes whose median stereo depth (`stereo`, CV_32F on key1's pixels,
// 0 = none) is at least (1 + see_through_ratio) times the median sensor depth on the measured
// pixels within ring_px of them. Holes that reach the image's edge are left out, and lines of
// hole pixels one or two pixels wide do not join holes. Empty when no hole qualifies.
cv::Mat SeeThroughRim(const RgbdFrame& key1, const cv::Mat& stereo,
                      const StereoFillOptions& options);

// key1/key2: colour (BGR) and metric depth with hole masks; key1_from_key2 maps points from
// keyframe 2's camera into keyframe 1's. Both frames use `camera`.
StereoFillResult FillHolesByStereo(const RgbdFrame& key1, const RgbdFrame& key2,
                                   const Camera& camera, const SE3& key1_from_key2,
                                   const StereoFillOptions& options, const ThirdView& third = {});

}  // namespace gf
