// The fusion's options (their bounds, FieldCheck) and its summaries (surfels/fusion.h).
#include <cstdio>

#include "acquisition/bounds.h"
#include "surfels/fusion.h"

namespace gf {

bool GlassOptions::Check(std::string* message) const {
  // A surfel's counts halve together before they overflow 16 bits.
  FieldCheck c(message);
  c.In("min_readings_on", min_readings_on, 1, 30000, "is more than a surfel's count holds")
      .In("min_through_share", min_through_share, 0, 1, kMoreThanOne)
      .In("edge_margin_px", edge_margin_px, 1, 64, "is wider than a depth edge moves")
      .Above("stable_confidence", stable_confidence, 0, kMaxCaptureFrames,
             kMoreFramesThanACapture)
      .Part("revolution", revolution);
  return c.ok();
}

bool FusionOptions::Check(std::string* message) const {
  // Confidence grows by a measurement's weight (at most 1) per frame that sees a surfel, so a
  // threshold beyond a day's capture is never reached. The radial weight's sigma is in half image
  // diagonals: at 1000 the corner's weight differs from 1 below single precision.
  constexpr double kMaxConfidence = kMaxCaptureFrames;
  constexpr double kFlatSigma = 1000;
  FieldCheck c(message);
  c.Above("min_depth_m", min_depth_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .Above("max_depth_m", max_depth_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .Require(max_depth_m > min_depth_m, "max_depth_m must be more than min_depth_m")
      .In("pixel_step", pixel_step, 1, kMaxImageSidePx, kLargerThanAnyImage)
      .In("fill_pixel_step", fill_pixel_step, 1, kMaxImageSidePx, kLargerThanAnyImage)
      .Above("max_depth_gap_m", max_depth_gap_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .Above("max_normal_angle_deg", max_normal_angle_deg, 0, 90,
             "is more than a surface facing the camera can turn")
      .In("normal_test_min_facing", normal_test_min_facing, 0, 1, kMoreThanOne)
      .Above("max_radius_ratio", max_radius_ratio, 0, kMaxRelativeDepth, kBeyondAnyDepthRange)
      .Above("confidence_sigma", confidence_sigma, 0, kFlatSigma, "is a flat weight")
      .Above("stable_confidence", stable_confidence, 0, kMaxConfidence, kMoreFramesThanACapture)
      .In("unstable_frames", unstable_frames, 1, kMaxCaptureFrames, kMoreFramesThanACapture)
      .Above("fill_weight", fill_weight, 0, kMaxRelativeWeight, kOutweighsBeyondRounding)
      .Above("fill_stable_confidence", fill_stable_confidence, 0, kMaxConfidence,
             kMoreFramesThanACapture)
      .In("fill_unstable_frames", fill_unstable_frames, 1, kMaxCaptureFrames,
          kMoreFramesThanACapture)
      .In("free_space_margin", free_space_margin, 0, kMaxRelativeDepth, kBeyondAnyDepthRange)
      .In("free_space_penalty", free_space_penalty, 0, kMaxConfidence, kMoreFramesThanACapture)
      .Above("max_neighbour_step", max_neighbour_step, 0, kMaxRelativeDepth, kBeyondAnyDepthRange)
      .In("merge_copies_every", merge_copies_every, 1, kMaxCaptureFrames, kMoreFramesThanACapture)
      .In("max_surfels", static_cast<double>(max_surfels), 1, kMaxMapSurfels,
          "takes more than the map's 16 GiB at 48 bytes a surfel")
      // The filter runs on the depth at half size.
      .In("normal_filter_px", normal_filter_px, 1, kMaxImageSidePx / 2,
          "is larger than any half-size image")
      .Above("normal_filter_depth_m", normal_filter_depth_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .In("normal_baseline_px", normal_baseline_px, 1, kMaxImageSidePx, kLargerThanAnyImage)
      .Part("glass", glass);
  return c.ok();
}

std::string FusionStats::BriefReport() const {
  char buffer[240];
  std::snprintf(buffer, sizeof(buffer),
                "fusion: %d pixels, %d merged, %d new, %d removed (%d seen through, %d redundant, "
                "%d over budget), %.1f ms",
                measured, merged, created, removed, contradicted, redundant, over_budget, ms);
  return buffer;
}

long SurfelCounts::total_stable() const {
  long n = 0;
  for (long c : stable) n += c;
  return n;
}

}  // namespace gf
