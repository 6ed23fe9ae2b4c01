#include "fill/stereo_fill.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "acquisition/bounds.h"
#include "acquisition/depth.h"
#include "acquisition/errors.h"
#include "acquisition/stats.h"
#include "fill/depth_candidates.h"

namespace gf {
namespace {

// What the methods of one pair share while they fill it.
struct FillContext {
  const StereoPair& pair;
  const StereoFillOptions& options;
  const Holes holes;
  const PhotometricCheck photometric;
  std::vector<float> errors, errors_m;  // candidate vs sensor on measured pixels, all methods
};

// The depth range that stereo searches: what the sensor measures in keyframe 1 (2nd to 98th
// percentile), widened by a quarter, within [min_depth_m, max_depth_m]. False when keyframe 1
// measures too little.
bool SearchRange(const RgbdFrame& key1, const ValidationOptions& options, double* near_m,
                 double* far_m, std::string* why) {
  const std::vector<float> measured = SortedDepthSample(key1.depth, 4);
  if (measured.size() < 100) {
    *why = "keyframe has almost no measured depth";
    return false;
  }
  *near_m = std::max(options.min_depth_m, 0.8 * measured[measured.size() / 50]);
  *far_m = std::min(options.max_depth_m, 1.25 * measured[measured.size() - 1 - measured.size() / 50]);
  if (!(*near_m < *far_m)) {
    *why = "measured depth outside [min_depth_m, max_depth_m]";
    return false;
  }
  return true;
}

// SGBM's depth, filtered and validated into *result. Returns whether it agreed with the sensor;
// *rim gets the rims of the holes it sees into that its validated depth fills (empty: none), and
// result->stereo_depth all of its depth.
bool FillBySgbm(const SgbmRectification& rect, FillContext* c, StereoFillResult* result,
                cv::Mat* rim) {
  const StereoFillOptions& o = c->options;
  const RgbdFrame& key1 = c->pair.key1;
  cv::Mat depth = RectifiedSgbmCandidates(rect, o.sgbm, o.validation.min_depth_m,
                                          o.validation.max_depth_m)
                      .Compute(c->pair, {});
  // All of it: what is dropped below stays empty (unless sweep_sgbm_rejects: the sweep retries).
  depth.copyTo(result->stereo_depth);
  *rim = SeeThroughRim(key1, depth, o.see_through, o.validation.ring_px,
                       o.validation.min_ring_samples);
  if (!rim->empty())
    DropNearSideWithinHoles(key1.hole_mask, o.see_through.near_side_px, o.depth_steps.jump, *rim,
                            &depth);
  const cv::Mat filtered = WithoutDepthSteps(depth, o.depth_steps.far_side_px,
                                             o.depth_steps.near_side_px, o.depth_steps.jump);
  const bool agrees = ValidateAndFill(filtered, key1, c->holes, c->photometric, o.validation,
                                      DepthSource::kStereo, result, &c->errors, &c->errors_m);
  if (!rim->empty())
    KeepRimsOfFilledHoles(c->holes, result->fill_mask, o.validation.min_ring_samples, rim);
  return agrees;
}

// The hole pixels the sweep fills: all holes of a forward pair, after SGBM those it found no
// depth for (or dropped, with sweep_sgbm_rejects); never the see-through rims (the sweep's
// windows there match the glass's edge), and projector shadows only with sweep_shadows.
cv::Mat SweepWanted(const RgbdFrame& key1, bool after_sgbm, const cv::Mat& rim,
                    const StereoFillOptions& o, const StereoFillResult& result) {
  cv::Mat wanted = key1.hole_mask != 0;
  if (after_sgbm)
    wanted &= o.sweep_sgbm_rejects ? result.fill_mask == 0 : result.stereo_depth == 0.f;
  if (!rim.empty()) wanted &= rim == 0;
  if (!o.sweep_shadows) wanted &= key1.hole_mask != static_cast<uint8_t>(HoleCode::kShadow);
  return wanted;
}

// The plane sweep over `wanted` and a validation ring around it, filtered and validated into
// *result (only `wanted` pixels are filled). Returns whether it agreed with the sensor.
bool FillBySweep(const cv::Mat& wanted, FillContext* c, StereoFillResult* result) {
  const StereoFillOptions& o = c->options;
  cv::Mat region;
  const int k = 2 * o.validation.ring_px + 1;
  cv::dilate(wanted, region, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
  const cv::Mat depth = PlaneSweepCandidates(o.plane_sweep).Compute(c->pair, region);
  depth.copyTo(result->stereo_depth, result->stereo_depth == 0.f);
  const cv::Mat filtered = WithoutDepthSteps(depth, o.depth_steps.far_side_px,
                                             o.depth_steps.near_side_px, o.depth_steps.jump);
  return ValidateAndFill(filtered, c->pair.key1, c->holes, c->photometric, o.validation,
                         DepthSource::kStereo, result, &c->errors, &c->errors_m, wanted);
}

}  // namespace

bool PairGeometryOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.Above("min_baseline_m", min_baseline_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .In("epipole_margin_px", epipole_margin_px, 0, kMaxImageSidePx, kLargerThanAnyImage);
  return c.ok();
}

bool StereoFillOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.Part("geometry", geometry)
      .Part("sgbm", sgbm)
      .Part("plane_sweep", plane_sweep)
      .Part("depth_steps", depth_steps)
      .Part("see_through", see_through)
      .Part("validation", validation)
      .Part("photometric", photometric);
  return c.ok();
}

const char* PairPathName(PairPath path) {
  switch (path) {
    case PairPath::kRectifiedSgbm: return "rectified_sgbm";
    case PairPath::kPlaneSweepForward: return "plane_sweep_forward";
    case PairPath::kPlaneSweepDegenerateRectification:
      return "plane_sweep_degenerate_rectification";
    case PairPath::kPlaneSweepRequested: return "plane_sweep_requested";
    case PairPath::kNone: break;
  }
  return "none";
}

const char* FillMethodName(FillMethod method) {
  switch (method) {
    case FillMethod::kRectifiedSgbm: return "rectified SGBM";
    case FillMethod::kPlaneSweep: return "plane sweep";
    case FillMethod::kSgbmThenSweep: return "rectified SGBM + plane sweep";
    case FillMethod::kNone: break;
  }
  return "";
}

std::string StereoFillResult::BriefReport() const {
  char buffer[400];
  std::snprintf(
      buffer, sizeof(buffer),
      "stereo fill (%s) %s: %d of %d hole pixels filled (%.1f%%), stereo vs sensor median "
      "error %.2f%% (%.1f mm); rejected by ring %d, by shadow geometry %d, by %s %d, seen through "
      "by another keyframe %d",
      FillMethodName(method), termination.c_str(), filled_pixels, hole_pixels,
      hole_pixels ? 100.0 * filled_pixels / hole_pixels : 0.0, 100.0 * stereo_error_median,
      1000.0 * stereo_error_median_m, rejected_by_ring, rejected_by_shadow,
      third_view_used ? "third view" : "(no third view)", rejected_by_photometry,
      rejected_by_free_space);
  return buffer;
}

bool EpipoleInsideImage(const Camera& camera, const SE3& a_from_b, double margin_px) {
  const Eigen::Vector3d c = a_from_b.translation();  // b's centre in a's frame
  if (std::abs(c.z()) < 1e-12) return false;         // sideways: epipole at infinity
  const double u = camera.fx * c.x() / c.z() + camera.cx, v = camera.fy * c.y() / c.z() + camera.cy;
  return u > -margin_px && v > -margin_px && u < camera.width + margin_px &&
         v < camera.height + margin_px;
}

bool IsForwardPair(const Camera& camera, const SE3& key1_from_key2, double margin_px) {
  return EpipoleInsideImage(camera, key1_from_key2, margin_px) ||
         EpipoleInsideImage(camera, key1_from_key2.Inverse(), margin_px);
}

StereoFillResult FillHolesByStereo(const RgbdFrame& key1, const RgbdFrame& key2,
                                   const Camera& camera, const SE3& key1_from_key2,
                                   const StereoFillOptions& options, const ThirdView& third,
                                   const std::vector<ThirdView>& witnesses) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  GF_CHECK(key1.color.type() == CV_8UC3 && key2.color.type() == CV_8UC3 &&
               key1.depth.type() == CV_32FC1 && key1.hole_mask.type() == CV_8UC1,
           "need BGR colour, metric depth and hole masks");
  StereoFillResult result;
  static_cast<DepthFill&>(result) = SensorOnly(key1);
  result.stereo_depth = cv::Mat::zeros(key1.depth.size(), CV_32FC1);
  if (key1_from_key2.TranslationNorm() < options.geometry.min_baseline_m) {
    result.termination = "baseline too short";
    return result;
  }
  const bool forward = IsForwardPair(camera, key1_from_key2, options.geometry.epipole_margin_px);
  if (forward && !options.plane_sweep_forward) {
    result.termination = "forward motion (epipole inside the image)";
    return result;
  }
  StereoPair pair{key1, key2, camera, key1_from_key2, third};
  if (!SearchRange(key1, options.validation, &pair.near_m, &pair.far_m, &result.termination))
    return result;
  FillContext c{pair, options, FindHoles(key1.hole_mask),
                PhotometricCheck(key1, third, camera, options.photometric), {}, {}};
  result.third_view_used = c.photometric.active();
  bool sgbm = !forward && !options.plane_sweep_always;
  result.path = forward ? PairPath::kPlaneSweepForward
                : sgbm  ? PairPath::kRectifiedSgbm
                        : PairPath::kPlaneSweepRequested;
  if (sgbm) {
    result.rectification = RectifyForSgbm(camera, key1_from_key2, pair.near_m, pair.far_m,
                                          options.sgbm);
    if (!result.rectification.usable) {
      // A degenerate rectification: the plane sweep, which needs none, fills the pair.
      sgbm = false;
      result.path = PairPath::kPlaneSweepDegenerateRectification;
      result.sgbm_refused = result.rectification.refusal;
    }
  }
  bool agrees = false;  // some method agreed with the sensor
  cv::Mat rim;          // the rims of the holes SGBM sees into (empty: none)
  cv::Mat sgbm_filled;  // the pixels SGBM filled
  if (sgbm) {
    result.method = FillMethod::kRectifiedSgbm;
    agrees = FillBySgbm(result.rectification, &c, &result, &rim);
    sgbm_filled = result.fill_mask.clone();
  }
  if (!sgbm || options.plane_sweep_after_sgbm) {
    if (!sgbm) result.method = FillMethod::kPlaneSweep;
    const cv::Mat wanted = SweepWanted(key1, sgbm, rim, options, result);
    if (cv::countNonZero(wanted) > 0) {
      if (sgbm) result.method = FillMethod::kSgbmThenSweep;
      agrees |= FillBySweep(wanted, &c, &result);
    }
  }
  result.stereo_error_median = c.errors.empty() ? 1.0 : Median(c.errors);
  result.stereo_error_median_m = c.errors_m.empty() ? 0.0 : Median(c.errors_m);
  if (!agrees) {
    result.termination = "stereo disagrees with the sensor (pose or matching)";
    return result;
  }
  if (options.validation.free_space_check) {
    std::vector<ThirdView> views = {{&key2, key1_from_key2}, third};
    views.insert(views.end(), witnesses.begin(), witnesses.end());
    RemoveSeenThrough(key1, views, camera, options.validation.free_space_margin, &result);
  }
  if (!sgbm_filled.empty() && cv::countNonZero(sgbm_filled) > 0)
    CorroborateFill(key1, {third}, camera, options.photometric, sgbm_filled, &result);
  CorroborateFill(key1, witnesses, camera, options.photometric, cv::Mat(), &result);
  result.success = true;
  result.termination = "ok";
  return result;
}

}  // namespace gf
