// Validating candidate depth (stereo, or any DepthCandidates) before it fills a keyframe's holes.
//
// A candidate depth image (keyframe 1's pixels, metres, 0 = none) fills a hole, or each
// ring_cell_px piece of a large one, only if it agrees with the sensor on the measured pixels in a
// ring around it (after a scale correction: a small pose error scales stereo depth locally), and
// only if it agrees with the sensor over the whole image. In a projector shadow the depth must lie
// nearer the shadow's far side than its near one (the shadow is the far surface). Where a third
// keyframe sees the filled point, its colour there must match keyframe 1's (PhotometricCheck).
// Measured pixels are never changed. Each filled pixel gets a confidence: ring agreement times
// photometric agreement. Views that took no part in measuring a fill may corroborate it
// (CorroborateFill), which fusion counts as a second keyframe's agreement.
//
// No threads, no I/O.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"

namespace gf {

struct ValidationOptions {
  double min_depth_m = 0.3;  // filled depths outside [min_depth_m, max_depth_m] are dropped
  double max_depth_m = 6.0;
  int ring_px = 6;            // validation ring around each hole, pixels
  int min_ring_samples = 15;  // holes with fewer candidate/sensor pairs in the ring stay empty
  int ring_cell_px = 40;      // large holes are judged piecewise, by the ring in each cell of this
                              // size, pixels (0: whole holes only)
  double max_ring_error = 0.03;       // median relative error allowed in the ring (after scaling)
  bool ring_scale_correction = true;  // scale each hole's depth by its ring's sensor/stereo ratio
  double max_ring_scale = 0.10;       // ... when that ratio is within 1 +- this (< 1)
  double max_pair_error = 0.08;  // median relative error over the whole image, else nothing fills
  // A filled point that another keyframe's sensor sees through (RemoveSeenThrough: all of the 3x3
  // measured pixels around its projection farther than it by free_space_margin, relative) lies
  // in space that keyframe saw empty, and is dropped. The margin is fusion's free_space_margin:
  // the map applies a like rule to its surfels (there five measured pixels of the 3x3 suffice),
  // but only with the sensor frames that come after a fill reaches it.
  bool free_space_check = true;
  double free_space_margin = 0.03;
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

struct PhotometricOptions {
  int patch_px = 15;  // patch side compared in the third view, pixels (odd, 3..99)
  // A hole pixel's patch uses keyframe 1's hole pixels only, so that a measured surface beside
  // the hole (a label above clear glass) cannot make it match at that surface's depth.
  bool hole_patches = true;
  double min_ncc = 0.5;               // textured patches must correlate at least this much
  double min_patch_std = 4.0;         // below this grey-level spread a patch is textureless ...
  double max_mean_difference = 25.0;  // ... and then only the mean grey levels are compared
  double occlusion_margin = 0.05;     // third view's sensor nearer by this (relative): hidden there
  // A view that took no part in measuring a fill corroborates it (CorroborateFill) where both
  // patches are textured and correlate at least min_ncc, and where a change of the depth by
  // corroboration_depth_step (relative) would move the point in that view by
  // corroboration_shift_px pixels or more: only there does the correlation test the depth at that
  // precision. Fusion confirms a corroborated fill without waiting for another keyframe's fill.
  double corroboration_depth_step = 0.03;
  double corroboration_shift_px = 1.0;
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

// Optional third keyframe for the photometric check.
struct ThirdView {
  const RgbdFrame* frame = nullptr;  // null: no check
  SE3 key1_from_key3;
};

// The filled depth of a keyframe and where each pixel came from.
struct DepthFill {
  cv::Mat filled_depth;  // CV_32F: the sensor's depth plus the filled pixels
  cv::Mat fill_mask;     // CV_8U: 255 where a hole was filled
  cv::Mat source;        // CV_8U: DepthSource per pixel of filled_depth
  cv::Mat confidence;    // CV_32F in [0, 1]: 1 on sensor pixels, the fill's confidence on filled
                         // ones (ring agreement times photometric agreement), 0 elsewhere
  cv::Mat corroborated;  // CV_8U: 255 where a view independent of the fill's pair corroborates
                         // the filled depth (PhotometricCheck::Agreement), 0 elsewhere
  int hole_pixels = 0;   // pixels the sensor left empty
  int filled_pixels = 0;
  int rejected_by_ring = 0;        // hole pixels with depth whose hole failed the ring test
  int rejected_by_photometry = 0;  // ... that the third view contradicted
  int rejected_by_shadow = 0;      // ... in projector shadows, nearer the shadow's near side
  int rejected_by_free_space = 0;  // filled pixels another keyframe's sensor saw through
};
// The keyframe's sensor depth, nothing filled yet.
DepthFill SensorOnly(const RgbdFrame& key1);

// Keyframe 1's holes for the ring validation: for every pixel, the distance to the nearest hole
// pixel and that hole's label (connected component), computed once per keyframe.
struct Holes {
  cv::Mat distance;  // CV_32F pixels, 0 on holes
  cv::Mat labels;    // CV_32S
  size_t count = 0;  // labels are < count
};
Holes FindHoles(const cv::Mat& hole_mask);

// Photometric check of a filled pixel in a third keyframe: the filled point, projected into the
// third view, must look like it does in keyframe 1 (NCC of patches, a hole pixel's over hole
// pixels only; mean grey levels for textureless patches). Points the third view's sensor sees
// behind a nearer surface, or outside its image, cannot be checked and pass. Holds references to
// its arguments.
class PhotometricCheck {
 public:
  PhotometricCheck(const RgbdFrame& key1, const ThirdView& third, const Camera& camera,
                   const PhotometricOptions& options);
  bool active() const { return !gray3_.empty(); }
  // 1 when unchecked, the patch correlation (or mean agreement) in (0, 1] when it passes, 0 when
  // the third view contradicts the depth. *corroborates (when given): whether textured patches
  // passed where the third view resolves a corroboration_depth_step change of the depth.
  double Agreement(int x, int y, double depth, bool* corroborates = nullptr) const;

 private:
  const Camera& camera_;
  const UndistortedPixels rays_;
  const PhotometricOptions& options_;
  ThirdView third_;
  cv::Mat gray1_, gray3_, holes1_;
  SE3 key3_from_key1_;
};

// Marks fill->corroborated on the filled pixels (those of `eligible` too, when given: CV_8U) that
// one of `views` corroborates (PhotometricCheck::Agreement). One pixel per 2x2 block is tested; a
// corroborated one marks the filled pixels of its block within corroboration_depth_step of its
// depth. Views with a null frame are skipped.
void CorroborateFill(const RgbdFrame& key1, const std::vector<ThirdView>& views,
                     const Camera& camera, const PhotometricOptions& options,
                     const cv::Mat& eligible, DepthFill* fill);

// Drops, in place, the filled pixels of *fill that one of `views` sees through: its sensor
// depth on all of the 3x3 pixels around the filled point's projection is farther than the point
// by more than free_space_margin (relative). One filled pixel per 2x2 block is tested; a
// seen-through one drops the block's filled pixels within free_space_margin of its depth. Counts
// them in rejected_by_free_space. Points outside a view, behind it, or where it measures less
// are not judged by it; null frames are skipped.
void RemoveSeenThrough(const RgbdFrame& key1, const std::vector<ThirdView>& views,
                       const Camera& camera, double free_space_margin, DepthFill* fill);

// Validates one candidate depth image (keyframe 1's pixels, 0 = none) against the sensor and fills
// the hole pixels that pass, are still empty in *fill and, when `fillable` is given (CV_8U),
// non-zero there, tagging them `source`. Appends the candidate-vs-sensor errors (relative, metres)
// on measured pixels. False, filling nothing, when the candidate disagrees with the sensor over
// the whole image (median error above max_pair_error).
bool ValidateAndFill(const cv::Mat& candidate, const RgbdFrame& key1, const Holes& holes,
                     const PhotometricCheck& photometric, const ValidationOptions& options,
                     DepthSource source, DepthFill* fill, std::vector<float>* errors,
                     std::vector<float>* errors_m, const cv::Mat& fillable = cv::Mat());

}  // namespace gf
