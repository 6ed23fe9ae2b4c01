// Filling a keyframe's depth holes by dense stereo with a second keyframe whose relative pose the
// tracker knows (the heart of GlassFusion: glass, shiny and dark surfaces that the Kinect cannot
// measure are still textured in colour).
//
// Steps (each method behind DepthCandidates, fill/depth_candidates.h):
//  1. the pair: too short a baseline is refused; a forward pair (the epipole inside an image) goes
//     to the plane sweep; a sideways one is rectified for SGBM (fill/rectified_sgbm.h), or goes to
//     the sweep when that rectification is degenerate (StereoFillResult::path says which);
//  2. SGBM over the disparities of keyframe 1's measured depth range; its depth next to depth
//     steps is dropped, and on the rims of the holes it sees into (clear glass) it is held to a
//     wider step rule (fill/depth_filters.h); then validated against the sensor and the third view
//     (fill/fill_validation.h);
//  3. the plane sweep over the holes SGBM found no depth for (or all holes of a forward pair),
//     leaving projector shadows and the see-through rims alone, filtered and validated the same
//     way.
// Only pixels the sensor left empty are filled; measured pixels are never changed. Each filled
// pixel carries a confidence and a source tag.
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
#include "fill/depth_filters.h"
#include "fill/fill_validation.h"
#include "fill/plane_sweep.h"
#include "fill/rectified_sgbm.h"

namespace gf {

// The geometry that decides whether and how a pair can serve stereo; pair selection
// (fill/keyframe_pairs.h) and the fill share one copy (the fill stage's `geometry` setting).
struct PairGeometryOptions {
  double min_baseline_m = 0.04;   // shorter baselines give too little parallax, metres
  double epipole_margin_px = 40;  // epipole inside an image or this close to it: forward motion
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
  bool operator==(const PairGeometryOptions& o) const {
    return min_baseline_m == o.min_baseline_m && epipole_margin_px == o.epipole_margin_px;
  }
};

struct StereoFillOptions {
  PairGeometryOptions geometry;
  bool plane_sweep_forward = true;     // forward pairs: plane sweep (else the pair is skipped)
  bool plane_sweep_always = false;     // the sweep for sideways pairs too, instead of SGBM
  bool plane_sweep_after_sgbm = true;  // sideways pairs: sweep the holes SGBM found no depth for
  // ... and the holes whose SGBM depth the filters or the validation dropped (a second try at an
  // answer that passes: on clear glass, most often the glass's own depth)
  bool sweep_sgbm_rejects = false;
  // Sweep projector shadows too (they lie at depth steps, where the sweep's windows carry the
  // front surface's depth into the hole; SGBM's left-right check handles them better)
  bool sweep_shadows = false;
  SgbmOptions sgbm;
  PlaneSweepOptions plane_sweep;
  DepthStepOptions depth_steps;
  SeeThroughOptions see_through;
  ValidationOptions validation;
  PhotometricOptions photometric;
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

// How a pair was served; PairPathName gives report.json's key for it.
enum class PairPath {
  kNone,                               // "none": the pair was not used
  kRectifiedSgbm,                      // "rectified_sgbm"
  kPlaneSweepForward,                  // "plane_sweep_forward": the epipole lies in an image
  kPlaneSweepDegenerateRectification,  // "plane_sweep_degenerate_rectification" (sgbm_refused)
  kPlaneSweepRequested,                // "plane_sweep_requested" (plane_sweep_always)
};
const char* PairPathName(PairPath path);

// What filled the pair's holes; FillMethodName gives its name ("" for kNone).
enum class FillMethod {
  kNone,
  kRectifiedSgbm,  // "rectified SGBM"
  kPlaneSweep,     // "plane sweep"
  kSgbmThenSweep,  // "rectified SGBM + plane sweep": the sweep over the holes SGBM left
};
const char* FillMethodName(FillMethod method);

struct StereoFillResult : DepthFill {
  bool success = false;
  std::string termination;  // "ok" or why the pair was not used
  FillMethod method = FillMethod::kNone;
  PairPath path = PairPath::kNone;
  std::string sgbm_refused;         // SgbmRectification::refusal for degenerate sideways pairs
  SgbmRectification rectification;  // of sideways pairs (BriefReport() for the log)
  cv::Mat stereo_depth;             // CV_32F metres in keyframe 1's image, 0 = none (all stereo)
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

// key1/key2: colour (BGR) and metric depth with hole masks; key1_from_key2 maps points from
// keyframe 2's camera into keyframe 1's. Both frames use `camera`. The fill is corroborated
// (DepthFill::corroborated, CorroborateFill) by the third view where SGBM measured it (SGBM sees
// keyframes 1 and 2 alone; the plane sweep uses the third view), and by each of `witnesses`
// (views that no method uses) wherever it is filled.
StereoFillResult FillHolesByStereo(const RgbdFrame& key1, const RgbdFrame& key2,
                                   const Camera& camera, const SE3& key1_from_key2,
                                   const StereoFillOptions& options, const ThirdView& third = {},
                                   const std::vector<ThirdView>& witnesses = {});

}  // namespace gf
