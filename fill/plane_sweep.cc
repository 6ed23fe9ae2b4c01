#include "fill/plane_sweep.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <opencv2/imgproc.hpp>

#include "acquisition/bounds.h"
#include "acquisition/depth.h"
#include "acquisition/errors.h"
#include "fill/plane_sweep_kernels.h"

namespace gf {

namespace sweep_detail {

Spans SpansOf(const uint8_t* row, int n, int min_gap) {
  Spans spans;
  for (int x = 0; x < n;) {
    if (!row[x]) {
      ++x;
      continue;
    }
    int end = x;
    while (end < n && row[end]) ++end;
    if (!spans.empty() && x - spans.back().end < min_gap)
      spans.back().end = end;
    else
      spans.push_back({x, end});
    x = end;
  }
  return spans;
}

ActiveColumns::ActiveColumns(const cv::Mat& active, int half) {
  const int rows = active.rows, cols = active.cols, blocks = (rows + kBlockRows - 1) / kBlockRows;
  constexpr int kMinGap = 8;
  std::vector<uint8_t> in_block(static_cast<size_t>(blocks) * cols, 0);
  for (int y = 0; y < rows; ++y) {
    const uint8_t* a = active.ptr<uint8_t>(y);
    uint8_t* b = &in_block[static_cast<size_t>(y / kBlockRows) * cols];
    for (int x = 0; x < cols; ++x) b[x] |= a[x] != 0;
  }
  for (int i = 0; i < blocks; ++i)
    block.push_back(SpansOf(&in_block[static_cast<size_t>(i) * cols], cols, kMinGap));
  std::vector<uint8_t> row(cols), wide(cols);
  for (int y = 0; y < rows; ++y) {
    // The blocks whose output rows y - half .. y + half read row y.
    std::fill(row.begin(), row.end(), 0);
    const int first = std::max(0, y - half) / kBlockRows,
              last = std::min(rows - 1, y + half) / kBlockRows;
    for (int i = first; i <= last; ++i)
      for (const Span& s : block[i]) std::fill(&row[s.begin], &row[0] + s.end, 1);
    sums.push_back(SpansOf(row.data(), cols, kMinGap));
    std::fill(wide.begin(), wide.end(), 0);
    for (const Span& s : sums.back())
      std::fill(&wide[std::max(0, s.begin - half)], &wide[0] + std::min(cols, s.end + half), 1);
    sample.push_back(SpansOf(wide.data(), cols, kMinGap));
    // Those of the block of output row y - half are Slide's.
    if (y >= half)
      for (const Span& s : block[(y - half) / kBlockRows])
        std::fill(&row[s.begin], &row[0] + s.end, 0);
    carried.push_back(SpansOf(row.data(), cols, 1));
  }
}

}  // namespace sweep_detail

bool PlaneSweepOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.In("window_px", window_px, 3, kMaxImageSidePx, kLargerThanAnyImage)
      .Require(window_px % 2 == 1, "window_px must be odd")
      .In("max_planes", max_planes, 3, 250,
          "is more planes than the sweep allows (its time grows with them)")
      .Above("max_step_px", max_step_px, 0, kMaxImageSidePx, kLargerThanAnyImage)
      .Above("min_ncc", min_ncc, -1, 1, kMoreThanOne)
      .Require(min_ncc < 1, "min_ncc must be less than 1 (no window correlates better)")
      .In("min_uniqueness", min_uniqueness, 0, 1, kMoreThanOne)
      .Require(min_uniqueness < 1, "min_uniqueness must be less than 1")
      .In("min_parallax_px", min_parallax_px, 0, kMaxImageSidePx, kLargerThanAnyImage)
      .In("min_texture", min_texture, 0, kMaxGreyLevel, kBeyondGreyLevels)
      .Above("min_window_inside", min_window_inside, 0, 1, kMoreThanOne)
      // Costs are 1 - NCC in hundredths (0-200): a smoothness penalty beyond 1000 outweighs five
      // pixels' whole cost range, and a textureless window costs at most what the worst match does.
      .In("smooth_small", smooth_small, 0, 1000, "outweighs the matching cost")
      .In("smooth_large", smooth_large, smooth_small, 1000, "outweighs the matching cost")
      .In("textureless_cost", textureless_cost, 0, 200, "is more than the worst match costs")
      .In("downscale", downscale, 1, 4, "shrinks the images more than the sweep allows")
      .In("context_px", context_px, 0, kMaxImageSidePx, kLargerThanAnyImage);
  return c.ok();
}

std::string PlaneSweepResult::BriefReport() const {
  char buffer[160];
  std::snprintf(buffer, sizeof(buffer), "plane sweep: %d planes, %d of %d pixels accepted", planes,
                accepted_pixels, requested_pixels);
  return buffer;
}

namespace {

using sweep_detail::AccumulateCorrelation;
using sweep_detail::ActiveColumns;
using sweep_detail::AggregatePass;
using sweep_detail::CostRow;
using sweep_detail::FirstMinimum;
using sweep_detail::GrayFloat;
using sweep_detail::KeyframeRow;
using sweep_detail::kUncovered;
using sweep_detail::Minimum;
using sweep_detail::Span;
using sweep_detail::ViewData;
using sweep_detail::WindowSums;

// Everything the sweep works on, at working size (undistorted, shrunk by `downscale`): the
// images, keyframe 1's window statistics over the region's bounding box (roi), the views.
struct SweepWork {
  Camera camera;  // the working images' pinhole camera
  cv::Size size;
  Eigen::Matrix3d k, k_inv;
  cv::Mat cover1, gray1, region;  // keyframe 1's coverage, grey level, wanted pixels
  std::vector<ViewData> views;
  double max_baseline = 0;
  cv::Rect roi;
  cv::Mat i_roi, c_roi, h_roi;  // grey level, coverage and hole weight in the roi
  cv::Mat n1, mean_i, var_i;    // keyframe 1's window share, mean and variance
  cv::Mat use_hole;             // 1 where a hole pixel's window uses hole pixels only
  bool hole_windows() const { return !use_hole.empty(); }
};

// Keyframe 1's window statistics for window weights w: the weighted share of the window (n1),
// mean and variance of its grey level.
void WindowStatistics(const cv::Mat& i_roi, const cv::Mat& w, int window, cv::Mat* n1,
                      cv::Mat* mean, cv::Mat* var) {
  const cv::Size box(window, window);
  const cv::Mat iw = i_roi.mul(w);
  cv::boxFilter(w, *n1, CV_32F, box, cv::Point(-1, -1), true, cv::BORDER_CONSTANT);
  cv::boxFilter(iw, *mean, CV_32F, box, cv::Point(-1, -1), true, cv::BORDER_CONSTANT);
  cv::boxFilter(iw.mul(i_roi), *var, CV_32F, box, cv::Point(-1, -1), true, cv::BORDER_CONSTANT);
  cv::max(*n1, 1e-6, *n1);
  cv::divide(*mean, *n1, *mean);
  cv::divide(*var, *n1, *var);
  *var -= mean->mul(*mean);
}

// Undistorts and shrinks the images, and finds the region's bounding box. Box filters keep
// running sums, so a NaN would poison whole rows: pixels outside an image are 0 and tracked by a
// coverage image instead; correlation windows are weighted by keyframe 1's coverage, so windows
// that cross its image border use the part inside.
SweepWork PrepareImages(const RgbdFrame& key1, const std::vector<SweepView>& views,
                        const Camera& camera, const cv::Mat& mask,
                        const PlaneSweepOptions& options) {
  SweepWork w;
  const cv::Size size = mask.size();
  const bool distorted = camera.HasDistortion();
  cv::Mat map_x, map_y;
  if (distorted) camera.UndistortionMaps(&map_x, &map_y);
  auto undistort = [&](const cv::Mat& image, int interpolation) {
    if (!distorted) return image;
    cv::Mat out;
    cv::remap(image, out, map_x, map_y, interpolation, cv::BORDER_CONSTANT, cv::Scalar(0));
    return out;
  };
  w.camera = camera.Scaled(1.0 / options.downscale);
  w.size = cv::Size(w.camera.width, w.camera.height);
  w.k = w.camera.K();
  w.k_inv = w.k.inverse();
  const cv::Mat cover_full = undistort(cv::Mat(size, CV_32F, cv::Scalar(1.f)), cv::INTER_NEAREST);
  cv::resize(cover_full, w.cover1, w.size, 0, 0, cv::INTER_AREA);
  // Grey levels at working size: the mean over the covered part of each cell, 0 outside.
  auto shrink_gray = [&](const cv::Mat& bgr) {
    cv::Mat gray = undistort(GrayFloat(bgr), cv::INTER_LINEAR).mul(cover_full), out;
    cv::resize(gray, out, w.size, 0, 0, cv::INTER_AREA);
    cv::divide(out, cv::max(w.cover1, 1e-6), out);
    return out;
  };
  cv::threshold(w.cover1, w.cover1, 0.99, 1.0, cv::THRESH_BINARY);
  w.gray1 = shrink_gray(key1.color).mul(w.cover1);
  cv::Mat region_full = undistort(mask, cv::INTER_NEAREST);
  region_full.convertTo(region_full, CV_32F);
  cv::resize(region_full, w.region, w.size, 0, 0, cv::INTER_AREA);
  w.region = w.region > 0;  // a working pixel is wanted when any of its pixels is
  cv::dilate(w.region, w.region, cv::Mat());
  for (const SweepView& v : views) {
    GF_CHECK(v.frame != nullptr && v.frame->color.type() == CV_8UC3, "views need BGR colour");
    const SE3 view_from_key1 = v.key1_from_view.Inverse();
    cv::Mat gray = shrink_gray(v.frame->color);
    gray.setTo(kUncovered, w.cover1 == 0.f);
    w.views.push_back({gray, view_from_key1.RotationMatrix(), view_from_key1.translation()});
    w.max_baseline = std::max(w.max_baseline, view_from_key1.TranslationNorm());
  }
  // Work on the bounding box of the region, widened by the window.
  const int half = options.window_px / 2;
  w.roi = cv::boundingRect(w.region);
  w.roi.x -= half + 1;
  w.roi.y -= half + 1;
  w.roi.width += 2 * half + 2;
  w.roi.height += 2 * half + 2;
  w.roi &= cv::Rect(0, 0, w.size.width, w.size.height);
  w.i_roi = w.gray1(w.roi);
  w.c_roi = w.cover1(w.roi);
  if (options.hole_windows) {
    // Keyframe 1's hole share of its coverage. Projector-shadow pixels are left out: they show
    // the background beside a foreground's edge, which a no-return surface's window (clear glass
    // beside the shadow it casts) would otherwise match at that edge's depth.
    const cv::Mat own_holes =
        (key1.hole_mask != 0) & (key1.hole_mask != static_cast<uint8_t>(HoleCode::kShadow));
    cv::Mat holes_full = undistort(own_holes, cv::INTER_NEAREST), holes;
    holes_full.convertTo(holes_full, CV_32F, 1.0 / 255);
    cv::resize(holes_full, holes, w.size, 0, 0, cv::INTER_AREA);
    w.h_roi = holes(w.roi).mul(w.c_roi);
  }
  return w;
}

// Keyframe 1's window statistics, weighted by its coverage; with hole windows, a hole pixel's
// window uses the hole pixels only where they fill at least min_window_inside of it, and its
// statistics replace the full window's there.
void KeyframeWindows(const PlaneSweepOptions& options, SweepWork* w) {
  WindowStatistics(w->i_roi, w->c_roi, options.window_px, &w->n1, &w->mean_i, &w->var_i);
  if (w->h_roi.empty()) return;
  cv::Mat n1_hole, mean_hole, var_hole;
  WindowStatistics(w->i_roi, w->h_roi, options.window_px, &n1_hole, &mean_hole, &var_hole);
  const cv::Mat selected = (w->h_roi >= 0.5f) & (n1_hole >= options.min_window_inside);
  if (cv::countNonZero(selected) == 0) return;
  selected.convertTo(w->use_hole, CV_32F, 1.0 / 255);
  n1_hole.copyTo(w->n1, selected);
  mean_hole.copyTo(w->mean_i, selected);
  var_hole.copyTo(w->var_i, selected);
}

// The roi pixels within context_px of the region (all of them when that reaches past the roi).
cv::Mat ActivePixels(const SweepWork& w, const PlaneSweepOptions& options) {
  const int reach = (options.context_px + options.downscale - 1) / options.downscale;
  if (reach >= std::max(w.roi.width, w.roi.height))
    return cv::Mat(w.roi.size(), CV_8UC1, cv::Scalar(1));
  cv::Mat active;
  cv::dilate(w.region(w.roi), active,
             cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * reach + 1, 2 * reach + 1)));
  return active;
}

// The matching cost of every plane at every roi pixel, pixel-major (cost[p * planes + d]):
// 100 * (1 - mean NCC over the views that see it) in [0, 200], textureless_cost where keyframe
// 1's window is flat or no view sees it (neutral: aggregation then carries the neighbours'), and
// at the pixels beyond context_px of the region.
std::unique_ptr<uint8_t[]> CostVolume(const SweepWork& w, int planes, double w_far, double dw,
                                      const PlaneSweepOptions& options) {
  const int rows = w.roi.height, cols = w.roi.width;
  const size_t pixels = static_cast<size_t>(rows) * cols;
  std::unique_ptr<uint8_t[]> cost(new uint8_t[pixels * planes]);  // every entry written below
  Eigen::Matrix3d shift = Eigen::Matrix3d::Identity();            // ROI pixel -> full image pixel
  shift(0, 2) = w.roi.x;
  shift(1, 2) = w.roi.y;
  cv::Mat sum(rows, cols, CV_32F), count(rows, cols, CV_32F), seen(rows, cols, CV_32F);
  const bool hole_windows = w.hole_windows();
  WindowSums window_sums(rows, cols, options.window_px, hole_windows);
  std::vector<float> row_cost(cols);
  const float inv_area = 1.f / (options.window_px * options.window_px);
  const float min_var = static_cast<float>(options.min_texture * options.min_texture);
  const float min_inside = static_cast<float>(options.min_window_inside);
  const float neutral = static_cast<float>(options.textureless_cost);
  // CostRow's value where no view sees a pixel, as a cost byte.
  const uint8_t neutral_byte =
      static_cast<uint8_t>(std::clamp(static_cast<int>(neutral + 0.5f), 0, 200));
  const ActiveColumns active(ActivePixels(w, options), options.window_px / 2);
  cv::Mat inv_n(rows, cols, CV_32F);  // inv_area / keyframe 1's window coverage, once
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x) inv_n.at<float>(y, x) = inv_area / w.n1.at<float>(y, x);
  // Costs are written plane-major for a block of planes, then moved into the pixel-major volume
  // a block at a time (contiguous bytes per pixel instead of one scattered byte per plane).
  constexpr int kBlock = 16;
  std::vector<uint8_t> block(static_cast<size_t>(kBlock) * pixels);
  for (int plane = 0; plane < planes; ++plane) {
    const double inverse_depth = w_far + plane * dw;
    for (const ViewData& v : w.views) {
      const bool first = &v == &w.views.front();  // writes sum, count and seen; the others add
      Eigen::Matrix3d h = v.rotation;
      h.col(2) += v.translation * inverse_depth;  // R + t n^T / z with n = (0, 0, 1)
      // Correlation over keyframe 1's covered pixels of each window.
      window_sums.Run(v, w.k * h * w.k_inv * shift, w.i_roi, w.c_roi, w.h_roi, active,
                      [&](int y, const float* m, const sweep_detail::Spans& spans) {
                        const KeyframeRow k{w.n1.ptr<float>(y), inv_n.ptr<float>(y),
                                            w.mean_i.ptr<float>(y), w.var_i.ptr<float>(y),
                                            hole_windows ? w.use_hole.ptr<float>(y) : nullptr};
                        for (const Span& s : spans)
                          AccumulateCorrelation(m, k, cols, s.begin, s.end, inv_area, min_inside,
                                                min_var, first, sum.ptr<float>(y),
                                                count.ptr<float>(y), seen.ptr<float>(y));
                      });
    }
    uint8_t* plane_cost = &block[static_cast<size_t>(plane % kBlock) * pixels];
    for (int y = 0; y < rows; ++y) {
      uint8_t* out = plane_cost + static_cast<size_t>(y) * cols;
      std::fill(out, out + cols, neutral_byte);
      for (const Span& s : active.block[y / ActiveColumns::kBlockRows]) {
        CostRow(sum.ptr<float>(y), count.ptr<float>(y), w.var_i.ptr<float>(y), seen.ptr<float>(y),
                s.begin, s.end, min_var, neutral, row_cost.data());
        for (int x = s.begin; x < s.end; ++x)
          out[x] = static_cast<uint8_t>(std::clamp(static_cast<int>(row_cost[x]), 0, 200));
      }
    }
    if (plane % kBlock == kBlock - 1 || plane == planes - 1) {
      const int first = plane - plane % kBlock, n = plane % kBlock + 1;
      for (size_t p = 0; p < pixels; ++p)
        for (int b = 0; b < n; ++b) cost[p * planes + first + b] = block[b * pixels + p];
    }
  }
  return cost;
}

// How far a 3% depth change moves roi pixel (x, y) at depth z in the best-placed view that sees
// it, working pixels (0 when no view sees it).
double Parallax(const SweepWork& w, int x, int y, double z) {
  const Eigen::Vector3d ray = w.k_inv * Eigen::Vector3d(x + w.roi.x, y + w.roi.y, 1.0);
  double parallax = 0;
  for (const ViewData& v : w.views) {
    const Eigen::Vector3d a = v.rotation * ray * z + v.translation;
    const Eigen::Vector3d b = v.rotation * ray * (1.03 * z) + v.translation;
    if (a.z() <= 0 || b.z() <= 0) continue;
    const Eigen::Vector2d pa = (w.k * a).hnormalized(), pb = (w.k * b).hnormalized();
    if (pa.x() < 0 || pa.y() < 0 || pa.x() > w.size.width - 1 || pa.y() > w.size.height - 1)
      continue;
    parallax = std::max(parallax, (pa - pb).norm());
  }
  return parallax;
}

// Each wanted pixel's plane of least aggregated cost, refined to sub-plane precision by a
// parabola, when its window has texture, the correlation there is high enough, the minimum is
// distinct and a view gives enough parallax. Depth and score at working size.
void SelectDepths(const SweepWork& w, const uint8_t* cost, const uint16_t* total, int planes,
                  double w_far, double dw, const PlaneSweepOptions& options, cv::Mat* depth,
                  cv::Mat* score) {
  *depth = cv::Mat(w.size, CV_32F, cv::Scalar(0.f));
  *score = cv::Mat(w.size, CV_32F, cv::Scalar(0.f));
  const double min_var = options.min_texture * options.min_texture;
  const double min_parallax = options.min_parallax_px / options.downscale;  // working pixels
  const int rows = w.roi.height, cols = w.roi.width;
  for (int y = 0; y < rows; ++y) {
    const uint8_t* r = w.region.ptr<uint8_t>(y + w.roi.y) + w.roi.x;
    const float* vi = w.var_i.ptr<float>(y);
    for (int x = 0; x < cols; ++x) {
      if (!r[x]) continue;
      const size_t base = (static_cast<size_t>(y) * cols + x) * planes;
      const uint16_t* t = &total[base];
      const int bk = FirstMinimum(t, planes);
      const uint8_t c = cost[base + bk];
      // Flat windows carry no evidence of their own; aggregation would only copy a neighbour's
      // depth into them (across occlusion edges too), so they get none.
      if (!(vi[x] > min_var) || c > 100.0 * (1.0 - options.min_ncc)) continue;
      // The least cost more than one plane away from the best.
      const int after = std::min(bk + 2, planes);
      const int others =
          std::min(Minimum(t, std::max(bk - 1, 0)), Minimum(t + after, planes - after));
      if (t[bk] > (1.0 - options.min_uniqueness) * others) continue;
      double offset = 0;
      if (bk > 0 && bk + 1 < planes) {
        const double l = t[bk - 1], b = t[bk], rt = t[bk + 1];
        const double denominator = l - 2.0 * b + rt;
        if (denominator > 0) offset = std::clamp(0.5 * (l - rt) / denominator, -0.5, 0.5);
      }
      const double z = 1.0 / (w_far + (bk + offset) * dw);
      if (Parallax(w, x, y, z) < min_parallax) continue;
      depth->at<float>(y + w.roi.y, x + w.roi.x) = static_cast<float>(z);
      score->at<float>(y + w.roi.y, x + w.roi.x) = 1.f - c / 100.f;
    }
  }
}

}  // namespace

PlaneSweepResult SweepDepth(const RgbdFrame& key1, const std::vector<SweepView>& views,
                            const Camera& camera, const cv::Mat& mask, double min_depth_m,
                            double max_depth_m, const PlaneSweepOptions& options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  GF_CHECK(mask.type() == CV_8UC1 && mask.size() == key1.color.size(), "mask: CV_8U, image size");
  GF_CHECK(mask.cols == camera.width && mask.rows == camera.height, "images: the camera's size");
  GF_CHECK(min_depth_m > 0 && max_depth_m > min_depth_m, "need 0 < min_depth < max_depth");
  PlaneSweepResult result;
  result.depth = cv::Mat::zeros(mask.size(), CV_32FC1);
  result.score = cv::Mat::zeros(mask.size(), CV_32FC1);
  result.requested_pixels = cv::countNonZero(mask);
  if (result.requested_pixels == 0 || views.empty()) return result;
  SweepWork w = PrepareImages(key1, views, camera, mask, options);
  KeyframeWindows(options, &w);
  // Planes evenly spaced in inverse depth, close enough that no pixel jumps more than max_step_px.
  const double f = std::max(w.k(0, 0), w.k(1, 1));
  const double w_near = 1.0 / min_depth_m, w_far = 1.0 / max_depth_m;
  const double step_needed = options.max_step_px / (1.5 * f * std::max(w.max_baseline, 1e-6));
  result.planes = std::clamp(static_cast<int>(std::ceil((w_near - w_far) / step_needed)) + 1, 3,
                             options.max_planes);
  const int planes = result.planes;
  const double dw = (w_near - w_far) / (planes - 1);
  const std::unique_ptr<uint8_t[]> cost = CostVolume(w, planes, w_far, dw, options);
  // Aggregation along 8 paths (or none), then the best plane per pixel.
  const size_t entries = static_cast<size_t>(w.roi.area()) * planes;
  std::unique_ptr<uint16_t[]> total(new uint16_t[entries]);  // every entry written below
  if (options.smooth_large > 0) {
    for (bool forward : {true, false})
      AggregatePass(cost.get(), w.roi.height, w.roi.width, planes, forward, options.smooth_small,
                    options.smooth_large, total.get());
  } else {
    std::copy(cost.get(), cost.get() + entries, total.get());
  }
  cv::Mat depth_u, score_u;
  SelectDepths(w, cost.get(), total.get(), planes, w_far, dw, options, &depth_u, &score_u);
  // Back into keyframe 1's (distorted) pixel grid.
  const double scale = 1.0 / options.downscale;
  const UndistortedPixels undistorted(camera);
  for (int y = 0; y < mask.rows; ++y) {
    for (int x = 0; x < mask.cols; ++x) {
      if (!mask.at<uint8_t>(y, x)) continue;
      const Eigen::Vector2d u = undistorted.At(x, y);  // full size
      const int ux = static_cast<int>(std::lround((u.x() + 0.5) * scale - 0.5)),
                uy = static_cast<int>(std::lround((u.y() + 0.5) * scale - 0.5));
      if (ux < 0 || uy < 0 || ux >= w.size.width || uy >= w.size.height) continue;
      const float z = depth_u.at<float>(uy, ux);
      if (!(z > 0)) continue;
      result.depth.at<float>(y, x) = z;
      result.score.at<float>(y, x) = score_u.at<float>(uy, ux);
      ++result.accepted_pixels;
    }
  }
  return result;
}

}  // namespace gf
