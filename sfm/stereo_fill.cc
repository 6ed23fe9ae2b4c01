#include "sfm/stereo_fill.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "acquisition/depth.h"
#include "acquisition/errors.h"
#include "acquisition/stats.h"
#include "sfm/plane_sweep.h"

namespace gf {
namespace {

// Photometric check of a filled pixel in a third keyframe: the filled point, projected into the
// third view, must look like it does in keyframe 1 (NCC of patches, a hole pixel's over hole
// pixels only; mean grey levels for textureless patches). Points the third view's sensor sees
// behind a nearer surface, or outside its image, cannot be checked and pass.
class PhotometricCheck {
 public:
  PhotometricCheck(const RgbdFrame& key1, const ThirdView& third, const Camera& camera,
                   const StereoFillOptions& options)
      : camera_(camera), rays_(camera), options_(options), third_(third) {
    if (third.frame == nullptr || third.frame->color.empty()) return;
    cv::cvtColor(key1.color, gray1_, cv::COLOR_BGR2GRAY);
    cv::cvtColor(third.frame->color, gray3_, cv::COLOR_BGR2GRAY);
    holes1_ = key1.hole_mask;
    key3_from_key1_ = third.key1_from_key3.Inverse();
  }
  bool active() const { return !gray3_.empty(); }

  // 1 when unchecked, the patch correlation (or mean agreement) in (0, 1] when it passes, 0 when
  // the third view contradicts the depth.
  double Agreement(int x, int y, double depth) const {
    if (!active()) return 1.0;
    const int r = options_.photometric_patch_px / 2;
    const Eigen::Vector2d n = rays_.Ray(x, y);
    const Eigen::Vector3d p3 =
        key3_from_key1_ * Eigen::Vector3d(n.x() * depth, n.y() * depth, depth);
    if (p3.z() <= 0) return 1.0;
    const Eigen::Vector2d q = camera_.ProjectDistorted(p3);
    const int qx = static_cast<int>(std::lround(q.x())), qy = static_cast<int>(std::lround(q.y()));
    if (qx - r < 0 || qy - r < 0 || qx + r >= gray3_.cols || qy + r >= gray3_.rows) return 1.0;
    if (x - r < 0 || y - r < 0 || x + r >= gray1_.cols || y + r >= gray1_.rows) return 1.0;
    const float sensor3 = third_.frame->depth.at<float>(qy, qx);
    if (sensor3 > 0 && sensor3 < p3.z() * (1.0 - options_.occlusion_margin)) return 1.0;
    // A hole pixel's patch uses keyframe 1's hole pixels only (photometric_hole_patches): a
    // measured surface next to the hole (a label above clear glass) would otherwise make the patch
    // match at that surface's depth.
    const bool hole_only = options_.photometric_hole_patches && holes1_.at<uint8_t>(y, x) != 0;
    double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
    int count = 0;
    for (int dy = -r; dy <= r; ++dy) {
      const uint8_t* holes = holes1_.ptr<uint8_t>(y + dy) + x;
      const uint8_t* a_row = gray1_.ptr<uint8_t>(y + dy) + x;
      const uint8_t* b_row = gray3_.ptr<uint8_t>(qy + dy) + qx;
      for (int dx = -r; dx <= r; ++dx) {
        if (hole_only && holes[dx] == 0) continue;
        const double a = a_row[dx], b = b_row[dx];
        ++count;
        sa += a;
        sb += b;
        saa += a * a;
        sbb += b * b;
        sab += a * b;
      }
    }
    const double ma = sa / count, mb = sb / count;
    const double va = std::max(0.0, saa / count - ma * ma),
                 vb = std::max(0.0, sbb / count - mb * mb);
    const double min_var = options_.min_patch_std * options_.min_patch_std;
    if (va < min_var || vb < min_var) {
      const double diff = std::abs(ma - mb);
      return diff <= options_.max_mean_difference ? 1.0 - 0.5 * diff / options_.max_mean_difference
                                                  : 0.0;
    }
    const double ncc = (sab / count - ma * mb) / std::sqrt(va * vb);
    return ncc >= options_.min_ncc ? ncc : 0.0;
  }

 private:
  const Camera& camera_;
  const UndistortedPixels rays_;
  const StereoFillOptions& options_;
  ThirdView third_;
  cv::Mat gray1_, gray3_, holes1_;
  SE3 key3_from_key1_;
};

// Keyframe 1's holes for the ring validation: for every pixel, the distance to the nearest hole
// pixel and that hole's label (connected component), computed once per keyframe.
struct Holes {
  cv::Mat distance;  // CV_32F pixels, 0 on holes
  cv::Mat labels;    // CV_32S
  size_t count = 0;  // labels are < count
};

Holes FindHoles(const cv::Mat& hole_mask) {
  Holes h;
  cv::distanceTransform(hole_mask == 0, h.distance, h.labels, cv::DIST_L2, 3, cv::DIST_LABEL_CCOMP);
  double max_label = 0;
  cv::minMaxLoc(h.labels, nullptr, &max_label);
  h.count = static_cast<size_t>(max_label) + 1;
  return h;
}

// Block matching spreads a textured surface's depth over the textureless pixels next to it
// (foreground fattening): a copy of `stereo` (CV_32F, 0 = none) without the depths that have a
// farther one within margin_near_px (the near side of a discontinuity) or a nearer one within
// margin_far_px, a discontinuity being a relative step over `jump`. Max/min filters over the
// window, so that a gap in the stereo (pixels the left-right check dropped) does not hide it.
cv::Mat WithoutEdgeMargins(const cv::Mat& stereo, int margin_far_px, int margin_near_px,
                           double jump) {
  if (margin_far_px <= 0 && margin_near_px <= 0) return stereo.clone();
  auto square = [](int r) {
    return cv::getStructuringElement(cv::MORPH_RECT, {2 * r + 1, 2 * r + 1});
  };
  // A margin of 0 compares each depth with itself, which never drops it.
  cv::Mat farthest, nearest;
  if (margin_near_px > 0)
    cv::dilate(stereo, farthest, square(margin_near_px));
  else
    farthest = stereo;
  if (margin_far_px > 0) {
    nearest = stereo.clone();
    nearest.setTo(std::numeric_limits<float>::max(), stereo <= 0.f);
    cv::erode(nearest, nearest, square(margin_far_px));
  } else {
    nearest = stereo;
  }
  const float up = static_cast<float>(1.0 + jump), down = static_cast<float>(1.0 - jump);
  cv::Mat kept = stereo.clone();
  for (int y = 0; y < stereo.rows; ++y) {
    float* k = kept.ptr<float>(y);
    const float* f = farthest.ptr<float>(y);
    const float* n = nearest.ptr<float>(y);
    for (int x = 0; x < stereo.cols; ++x)
      if (f[x] > k[x] * up || n[x] < k[x] * down) k[x] = 0.f;
  }
  return kept;
}

// Clear glass's rim is a colour edge at the glass's depth, and block matching spreads that depth
// over the background seen through the glass: inside a hole, a near depth beside a farther one.
// A glossy or dark object's border, by contrast, meets the measured background outside its hole.
// Drops, in place, the hole pixels' stereo depth that has a farther stereo depth on another hole
// pixel within margin_px (a step over `jump`); only on the pixels where `where` (CV_8U) is non-zero
// when it is given.
void DropNearSideWithinHoles(const cv::Mat& hole_mask, int margin_px, double jump, cv::Mat* stereo,
                             const cv::Mat& where = cv::Mat()) {
  if (margin_px <= 0) return;
  cv::Mat in_holes = stereo->clone();
  in_holes.setTo(0.f, hole_mask == 0);
  const cv::Mat kept = WithoutEdgeMargins(in_holes, 0, margin_px, jump);
  cv::Mat dropped = (in_holes > 0.f) & (kept <= 0.f);
  if (!where.empty()) dropped &= where != 0;
  stereo->setTo(0.f, dropped);
}

// Drops, in place, the stereo depth on the rim pixels (`rim`, CV_8U) that is nearer, by more than
// see_through_sensor_step, than the farthest sensor depth within see_through_sensor_px: the
// glass's edge, matched in front of the background that the sensor measures beside the glass.
void DropNearerThanSensorBeside(const RgbdFrame& key1, const cv::Mat& rim,
                                const StereoFillOptions& options, cv::Mat* stereo) {
  if (options.see_through_sensor_px <= 0) return;
  cv::Mat farthest = key1.depth.clone();
  farthest.setTo(0.f, key1.hole_mask != 0);
  const int side = 2 * options.see_through_sensor_px + 1;
  cv::dilate(farthest, farthest, cv::getStructuringElement(cv::MORPH_RECT, {side, side}));
  const float up = static_cast<float>(1.0 + options.see_through_sensor_step);
  for (int y = 0; y < rim.rows; ++y) {
    const uint8_t* r = rim.ptr<uint8_t>(y);
    const float* f = farthest.ptr<float>(y);
    float* s = stereo->ptr<float>(y);
    for (int x = 0; x < rim.cols; ++x)
      if (r[x] && s[x] > 0 && s[x] * up < f[x]) s[x] = 0.f;
  }
}

// Keeps, in place, the rim pixels of the holes where SGBM's validated depth filled at least
// min_filled pixels: where its depth did not pass validation, its view of the hole does not count.
void KeepRimsOfFilledHoles(const Holes& holes, const cv::Mat& fill_mask, int min_filled,
                           cv::Mat* rim) {
  std::vector<int> filled(holes.count, 0);
  for (int y = 0; y < fill_mask.rows; ++y)
    for (int x = 0; x < fill_mask.cols; ++x)
      if (fill_mask.at<uint8_t>(y, x)) ++filled[holes.labels.at<int>(y, x)];
  for (int y = 0; y < rim->rows; ++y)
    for (int x = 0; x < rim->cols; ++x)
      if (rim->at<uint8_t>(y, x) && filled[holes.labels.at<int>(y, x)] < min_filled)
        rim->at<uint8_t>(y, x) = 0;
}

// Validates one stereo depth image (keyframe 1's pixels, 0 = none) against the sensor and fills
// the hole pixels that pass, are still empty in *result and, when `fillable` is given (CV_8U),
// non-zero there. Appends the stereo-vs-sensor errors (relative, metres) on measured pixels.
// False, filling nothing, when the stereo disagrees with the sensor over the whole image (median
// error above max_pair_error).
bool ValidateAndFill(const cv::Mat& stereo_in, const RgbdFrame& key1, const Holes& holes_of,
                     const PhotometricCheck& photometric, const StereoFillOptions& options,
                     StereoFillResult* r, std::vector<float>* errors, std::vector<float>* errors_m,
                     const cv::Mat& fillable = cv::Mat()) {
  StereoFillResult& result = *r;
  const cv::Mat stereo = WithoutEdgeMargins(stereo_in, options.edge_margin_px,
                                            options.edge_margin_near_px, options.edge_jump);

  // Validation against the sensor: over the image, and in a ring around each hole.
  std::vector<float> all_errors;
  const cv::Mat& distance = holes_of.distance;
  const cv::Mat& labels = holes_of.labels;
  // Ring statistics per hole, and per piece of a hole (the hole cut by a grid of ring_cell_px
  // cells): a piece with enough ring samples of its own is judged by them, others by the hole's.
  const int cell =
      options.ring_cell_px > 0 ? options.ring_cell_px : std::max(stereo.cols, stereo.rows);
  const int cells_x = (stereo.cols + cell - 1) / cell, cells_y = (stereo.rows + cell - 1) / cell;
  const size_t holes = holes_of.count, cells = static_cast<size_t>(cells_x) * cells_y;
  auto piece_of = [&](int x, int y, int label) {
    return holes + static_cast<size_t>(label) * cells + static_cast<size_t>(y / cell) * cells_x +
           x / cell;
  };
  // Entries [0, holes): whole holes; [holes, holes + holes * cells): pieces.
  std::vector<std::vector<float>> ring_errors(holes + holes * cells);
  std::vector<std::vector<float>> ring_ratios(ring_errors.size());  // sensor / stereo
  for (int y = 0; y < stereo.rows; ++y) {
    for (int x = 0; x < stereo.cols; ++x) {
      const float s = stereo.at<float>(y, x), k = key1.depth.at<float>(y, x);
      if (!(s > 0) || !(k > 0)) continue;
      const float e = std::abs(s - k) / k;
      all_errors.push_back(e);
      errors_m->push_back(std::abs(s - k));
      if (distance.at<float>(y, x) <= options.ring_px) {
        const int label = labels.at<int>(y, x);
        for (size_t id : {static_cast<size_t>(label), piece_of(x, y, label)}) {
          ring_errors[id].push_back(e);
          ring_ratios[id].push_back(k / s);
        }
      }
    }
  }
  errors->insert(errors->end(), all_errors.begin(), all_errors.end());
  if (all_errors.empty() || Median(all_errors) > options.max_pair_error) return false;
  // Per hole or piece: the ring's median error decides; with ring_scale_correction the stereo
  // depth is first scaled by the ring's median sensor/stereo ratio (a small pose error scales
  // stereo depth locally), and the error left after that decides.
  std::vector<uint8_t> accept(ring_errors.size(), 0);
  std::vector<float> ring_median(ring_errors.size(), 1.f), ring_scale(ring_errors.size(), 1.f);
  for (size_t l = 0; l < ring_errors.size(); ++l) {
    if (static_cast<int>(ring_errors[l].size()) < options.min_ring_samples) continue;
    if (options.ring_scale_correction) {
      const float scale = Median(ring_ratios[l]);
      std::vector<float> left;
      for (float r : ring_ratios[l]) left.push_back(std::abs(r / scale - 1.f));
      ring_median[l] = Median(left);
      ring_scale[l] = scale;
      accept[l] = ring_median[l] <= options.max_ring_error &&
                  std::abs(scale - 1.f) <= options.max_ring_scale;
    } else {
      ring_median[l] = Median(ring_errors[l]);
      accept[l] = ring_median[l] <= options.max_ring_error;
    }
  }
  const uint8_t shadow = static_cast<uint8_t>(HoleCode::kShadow);
  for (int y = 0; y < stereo.rows; ++y) {
    const uint8_t* hole_row = key1.hole_mask.ptr<uint8_t>(y);
    const float* depth_row = key1.depth.ptr<float>(y);
    float shadow_near = 0, shadow_far = 0;  // the sensor's depths on either side of a shadow run
    for (int x = 0; x < stereo.cols; ++x) {
      if (hole_row[x] == 0) continue;  // measured: never overwritten
      if (hole_row[x] == shadow && (x == 0 || hole_row[x - 1] != shadow)) {
        int end = x;
        while (end < stereo.cols && hole_row[end] == shadow) ++end;
        const float left = x > 0 ? depth_row[x - 1] : 0.f;
        const float right = end < stereo.cols ? depth_row[end] : 0.f;
        shadow_near = std::min(left, right);
        shadow_far = std::max(left, right);
      }
      if (result.fill_mask.at<uint8_t>(y, x)) continue;  // filled by an earlier method
      if (!fillable.empty() && !fillable.at<uint8_t>(y, x)) continue;
      if (!(stereo.at<float>(y, x) > 0)) continue;
      const int hole = labels.at<int>(y, x);
      const size_t piece = piece_of(x, y, hole);
      const size_t label =
          static_cast<int>(ring_errors[piece].size()) >= options.min_ring_samples ? piece : hole;
      const float s = stereo.at<float>(y, x) * ring_scale[label];
      if (!accept[label]) {
        ++result.rejected_by_ring;
        continue;
      }
      // A projector shadow is the far surface hidden from the projector by the near one: stereo
      // depth nearer the near side is the near surface spread over the shadow (block matching's
      // foreground fattening, occluded in one view).
      if (hole_row[x] == shadow && shadow_near > 0 &&
          std::abs(s - shadow_near) <= std::abs(s - shadow_far)) {
        ++result.rejected_by_shadow;
        continue;
      }
      const double agreement = photometric.Agreement(x, y, s);
      if (agreement <= 0) {
        ++result.rejected_by_photometry;
        continue;
      }
      result.filled_depth.at<float>(y, x) = s;
      result.fill_mask.at<uint8_t>(y, x) = 255;
      result.source.at<uint8_t>(y, x) = static_cast<uint8_t>(DepthSource::kStereo);
      const double ring = ring_median[label] / options.max_ring_error;
      result.confidence.at<float>(y, x) = static_cast<float>(std::exp(-ring * ring) * agreement);
      ++result.filled_pixels;
    }
  }
  return true;
}

}  // namespace

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

bool StereoFillOptions::Check(std::string* message) const {
  auto fail = [&](const char* m) {
    if (message) *message = m;
    return false;
  };
  if (!(min_baseline_m > 0)) return fail("min_baseline_m must be positive");
  if (!(epipole_margin_px >= 0)) return fail("epipole_margin_px must be >= 0");
  if (!(min_depth_m > 0) || !(max_depth_m > min_depth_m))
    return fail("need 0 < min_depth_m < max_depth_m");
  if (edge_margin_px < 0 || edge_margin_near_px < 0 || hole_edge_margin_near_px < 0 ||
      !(edge_jump > 0))
    return fail("edge margins must be >= 0 and edge_jump positive");
  if (!(see_through_ratio > -1) || see_through_rim_px < 0 || see_through_margin_px < 0 ||
      see_through_sensor_px < 0 || !(see_through_sensor_step >= 0))
    return fail(
        "see_through_ratio must be > -1; see_through_rim_px, see_through_margin_px, "
        "see_through_sensor_px and see_through_sensor_step >= 0");
  if (ring_px < 1 || min_ring_samples < 1 || ring_cell_px < 0 || !(max_ring_error > 0) ||
      !(max_pair_error > 0))
    return fail("ring and error thresholds must be positive");
  if (photometric_patch_px < 3 || photometric_patch_px % 2 == 0 || !(min_ncc > -1) ||
      !(min_patch_std >= 0) || !(max_mean_difference > 0) || !(occlusion_margin >= 0))
    return fail("photometric check: odd patch >= 3, min_ncc > -1, positive thresholds");
  return sgbm.Check(message) && plane_sweep.Check(message);
}

std::string StereoFillResult::BriefReport() const {
  char buffer[300];
  std::snprintf(
      buffer, sizeof(buffer),
      "stereo fill (%s) %s: %d of %d hole pixels filled (%.1f%%), stereo vs sensor median "
      "error %.2f%% (%.1f mm); rejected by ring %d, by shadow geometry %d, by %s %d",
      method.c_str(), termination.c_str(), filled_pixels, hole_pixels,
      hole_pixels ? 100.0 * filled_pixels / hole_pixels : 0.0, 100.0 * stereo_error_median,
      1000.0 * stereo_error_median_m, rejected_by_ring, rejected_by_shadow,
      third_view_used ? "third view" : "(no third view)", rejected_by_photometry);
  return buffer;
}

cv::Mat SeeThroughRim(const RgbdFrame& key1, const cv::Mat& stereo,
                      const StereoFillOptions& options) {
  if (options.see_through_rim_px <= 0) return {};
  auto disk = [](int r) {
    return cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * r + 1, 2 * r + 1});
  };
  // Holes are judged without the lines of hole pixels one or two pixels wide (3x3 opening), which
  // join objects that stand apart: a shelf's front edge, seen at a grazing angle, joins a clear
  // vase's hole to a dark object's, whose depth in front of the ring would then decide for both.
  const cv::Mat in_hole = key1.hole_mask != 0;
  cv::Mat whole, labels;
  cv::morphologyEx(in_hole, whole, cv::MORPH_OPEN, cv::Mat::ones(3, 3, CV_8UC1));
  const int count = cv::connectedComponents(whole, labels, 8, CV_32S);  // label 0: no hole
  if (count < 2) return {};
  // Every pixel within ring_px of a hole takes its label (the largest where two are that near):
  // the ring's measured pixels, and the hole pixels that the opening took away.
  cv::Mat near;
  labels.convertTo(near, CV_32F);
  cv::dilate(near, near, disk(options.ring_px));
  std::vector<std::vector<float>> inside(count), ring(count);
  std::vector<uint8_t> at_edge(count, 0);
  for (int y = 0; y < stereo.rows; ++y) {
    const uint8_t* w = whole.ptr<uint8_t>(y);
    const uint8_t* h = in_hole.ptr<uint8_t>(y);
    const int* l = labels.ptr<int>(y);
    const float* n = near.ptr<float>(y);
    const float* s = stereo.ptr<float>(y);
    const float* k = key1.depth.ptr<float>(y);
    const bool edge_row = y == 0 || y == stereo.rows - 1;
    for (int x = 0; x < stereo.cols; ++x) {
      if (w[x]) {
        if (s[x] > 0) inside[l[x]].push_back(s[x]);
        // A hole that reaches the image's edge is not seen whole (ICL-NUIM's invalid border
        // frame is one): what SGBM sees in it is the scene going on out of view.
        if (edge_row || x == 0 || x == stereo.cols - 1) at_edge[l[x]] = 1;
      } else if (!h[x] && n[x] > 0 && k[x] > 0) {
        ring[static_cast<int>(n[x])].push_back(k[x]);
      }
    }
  }
  std::vector<uint8_t> sees_through(count, 0);
  bool any = false;
  const size_t enough = static_cast<size_t>(options.min_ring_samples);
  for (int i = 1; i < count; ++i) {
    if (at_edge[i] || inside[i].size() < enough || ring[i].size() < enough) continue;
    sees_through[i] = Median(std::move(inside[i])) >
                      (1.0 + options.see_through_ratio) * Median(std::move(ring[i]));
    any |= sees_through[i] != 0;
  }
  if (!any) return {};
  cv::Mat deep;  // hole pixels farther than see_through_rim_px from every measured pixel
  cv::erode(in_hole, deep, disk(options.see_through_rim_px));
  cv::Mat rim = cv::Mat::zeros(stereo.size(), CV_8UC1);
  for (int y = 0; y < rim.rows; ++y) {
    const uint8_t* h = in_hole.ptr<uint8_t>(y);
    const uint8_t* d = deep.ptr<uint8_t>(y);
    const float* n = near.ptr<float>(y);
    uint8_t* r = rim.ptr<uint8_t>(y);
    for (int x = 0; x < rim.cols; ++x)
      if (h[x] && !d[x] && sees_through[static_cast<int>(n[x])]) r[x] = 255;
  }
  return rim;
}

StereoFillResult FillHolesByStereo(const RgbdFrame& key1, const RgbdFrame& key2,
                                   const Camera& camera, const SE3& key1_from_key2,
                                   const StereoFillOptions& options, const ThirdView& third) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  GF_CHECK(key1.color.type() == CV_8UC3 && key2.color.type() == CV_8UC3 &&
               key1.depth.type() == CV_32FC1 && key1.hole_mask.type() == CV_8UC1,
           "need BGR colour, metric depth and hole masks");
  StereoFillResult result;
  result.filled_depth = key1.depth.clone();
  result.fill_mask = cv::Mat::zeros(key1.depth.size(), CV_8UC1);
  result.stereo_depth = cv::Mat::zeros(key1.depth.size(), CV_32FC1);
  result.hole_pixels = cv::countNonZero(key1.hole_mask);
  result.source = cv::Mat::zeros(key1.depth.size(), CV_8UC1);
  result.source.setTo(static_cast<uint8_t>(DepthSource::kSensor), key1.hole_mask == 0);
  result.confidence = cv::Mat::zeros(key1.depth.size(), CV_32FC1);
  result.confidence.setTo(1.f, key1.hole_mask == 0);

  if (key1_from_key2.TranslationNorm() < options.min_baseline_m) {
    result.termination = "baseline too short";
    return result;
  }
  const bool forward = IsForwardPair(camera, key1_from_key2, options.epipole_margin_px);
  if (forward && !options.plane_sweep_forward) {
    result.termination = "forward motion (epipole inside the image)";
    return result;
  }
  const PhotometricCheck photometric(key1, third, camera, options);
  result.third_view_used = photometric.active();
  bool sgbm = !forward && !options.plane_sweep_always;
  // The depth range that stereo searches: what the sensor measures in keyframe 1 (2nd to 98th
  // percentile), widened by a quarter, within [min_depth_m, max_depth_m].
  const std::vector<float> measured = SortedDepthSample(key1.depth, 4);
  if (measured.size() < 100) {
    result.termination = "keyframe has almost no measured depth";
    return result;
  }
  const double near = std::max(options.min_depth_m, 0.8 * measured[measured.size() / 50]);
  const double far =
      std::min(options.max_depth_m, 1.25 * measured[measured.size() - 1 - measured.size() / 50]);
  if (!(near < far)) {
    result.termination = "measured depth outside [min_depth_m, max_depth_m]";
    return result;
  }
  result.path = forward ? "plane_sweep_forward" : sgbm ? "rectified_sgbm" : "plane_sweep_requested";
  const Holes holes = FindHoles(key1.hole_mask);
  std::vector<float> errors, errors_m;  // stereo vs sensor on measured pixels, over all methods
  bool agrees = false;                  // some method agreed with the sensor
  cv::Mat see_through_rim;              // the rims of the holes SGBM sees into (empty: none)
  SgbmRectification rect;
  if (sgbm) {
    rect = RectifyForSgbm(camera, key1_from_key2, near, far, options.sgbm);
    result.rectification = rect;
    if (!rect.usable) {
      // A degenerate rectification: the plane sweep, which needs none, fills the pair.
      sgbm = false;
      result.path = "plane_sweep_degenerate_rectification";
      result.sgbm_refused = rect.refusal;
    }
  }
  if (sgbm) {
    cv::Mat stereo = cv::Mat::zeros(key1.depth.size(), CV_32FC1);
    // Stereo runs with the left camera of the pair first; when that is keyframe 2, its points are
    // moved into keyframe 1 with the known pose.
    const SE3 key1_from_points = rect.swapped ? key1_from_key2 : SE3();
    std::vector<Eigen::Vector3d> points;
    points = SgbmPoints(rect, key1, key2, camera, options.sgbm);
    // Back into keyframe 1's image; the nearest surface wins.
    for (const Eigen::Vector3d& q : points) {
      const Eigen::Vector3d p = key1_from_points * q;
      if (p.z() < options.min_depth_m || p.z() > options.max_depth_m) continue;
      const Eigen::Vector2d px = camera.ProjectDistorted(p);
      const int x = static_cast<int>(std::lround(px.x())),
                y = static_cast<int>(std::lround(px.y()));
      if (x < 0 || y < 0 || x >= stereo.cols || y >= stereo.rows) continue;
      float& cell = stereo.at<float>(y, x);
      if (cell == 0.f || p.z() < cell) cell = static_cast<float>(p.z());
    }
    result.method = "rectified SGBM";
    // All of it: what is dropped below stays empty (unless sweep_sgbm_rejects: the sweep retries).
    stereo.copyTo(result.stereo_depth);
    see_through_rim = SeeThroughRim(key1, stereo, options);
    DropNearSideWithinHoles(key1.hole_mask, options.hole_edge_margin_near_px, options.edge_jump,
                            &stereo);
    if (!see_through_rim.empty()) {
      DropNearSideWithinHoles(key1.hole_mask, options.see_through_margin_px, options.edge_jump,
                              &stereo, see_through_rim);
      DropNearerThanSensorBeside(key1, see_through_rim, options, &stereo);
    }
    agrees =
        ValidateAndFill(stereo, key1, holes, photometric, options, &result, &errors, &errors_m);
    if (!see_through_rim.empty())
      KeepRimsOfFilledHoles(holes, result.fill_mask, options.min_ring_samples, &see_through_rim);
  }
  // Plane sweep: for forward pairs (rectification degenerates) or when asked for every pair, over
  // the holes and a validation ring around them; after SGBM (plane_sweep_after_sgbm), over the
  // hole pixels SGBM found no depth for. Within the depth range the sensor measures in keyframe 1.
  // Only those pixels are filled from the sweep; the rest of its region is the validation ring.
  if (!sgbm || options.plane_sweep_after_sgbm) {
    cv::Mat wanted = key1.hole_mask != 0;
    // Where SGBM found a depth that the edge margins or the validation then dropped, the sweep
    // would be a second try at an answer that passes: on clear glass, most often the glass's own
    // depth instead of the background behind it (sweep_sgbm_rejects).
    if (sgbm)
      wanted &= options.sweep_sgbm_rejects ? result.fill_mask == 0 : result.stereo_depth == 0.f;
    // The rims of the holes SGBM sees into: the sweep's windows there match the glass's edge.
    if (!see_through_rim.empty()) wanted &= see_through_rim == 0;
    // Projector shadows lie at depth discontinuities by definition, where the sweep's windows
    // carry the front surface's depth into the hole: left to SGBM unless asked for.
    if (!options.sweep_shadows) wanted &= key1.hole_mask != static_cast<uint8_t>(HoleCode::kShadow);
    if (!sgbm) result.method = "plane sweep";
    if (cv::countNonZero(wanted) > 0) {
      cv::Mat region;
      const int k = 2 * options.ring_px + 1;
      cv::dilate(wanted, region, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
      std::vector<SweepView> views{{&key2, key1_from_key2}};
      if (third.frame != nullptr) views.push_back({third.frame, third.key1_from_key3});
      const PlaneSweepResult sweep =
          SweepDepth(key1, views, camera, region, near, far, options.plane_sweep);
      if (sgbm) result.method = "rectified SGBM + plane sweep";
      sweep.depth.copyTo(result.stereo_depth, result.stereo_depth == 0.f);
      agrees |= ValidateAndFill(sweep.depth, key1, holes, photometric, options, &result, &errors,
                                &errors_m, wanted);
    }
  }

  result.stereo_error_median = errors.empty() ? 1.0 : Median(errors);
  result.stereo_error_median_m = errors_m.empty() ? 0.0 : Median(errors_m);
  if (!agrees) {
    result.termination = "stereo disagrees with the sensor (pose or matching)";
    return result;
  }
  result.success = true;
  result.termination = "ok";
  return result;
}

}  // namespace gf
