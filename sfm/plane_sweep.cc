#include "sfm/plane_sweep.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "acquisition/depth.h"
#include "acquisition/errors.h"

namespace gf {
namespace {

// The inner loops are compiled twice, for AVX2 (twice the vector width) and for the baseline
// x86-64 (SSE2); the loader picks what the CPU has.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define GF_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define GF_VECTOR_CLONES
#endif

cv::Mat GrayFloat(const cv::Mat& bgr) {
  cv::Mat gray, f;
  cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
  gray.convertTo(f, CV_32F);
  return f;
}

// Grey level of view pixels outside the image: a bilinear sample with any share of one is below
// -0.5 (shares are at least ~1e-9 in float), so it is known as uncovered.
constexpr float kUncovered = -1e9f;

struct ViewData {
  cv::Mat gray;  // CV_32F: undistorted grey level at working size, kUncovered outside the image
  Eigen::Matrix3d rotation;  // view_from_key1
  Eigen::Vector3d translation;
};

// out[x] = in[x] + in[x + step] + ... + in[x + (count - 1) step] for x < n; one pass, so the sums
// vectorise over x. The common window sizes get a fixed count.
template <int kCount>
void SumFixed(const float* __restrict in, size_t step, int n, float* __restrict out) {
  for (int x = 0; x < n; ++x) {
    float a = in[x];
    for (int k = 1; k < kCount; ++k) a += in[x + k * step];
    out[x] = a;
  }
}
GF_VECTOR_CLONES void SumWindows(const float* in, size_t step, int count, int n, float* out) {
  switch (count) {
    case 3:
      return SumFixed<3>(in, step, n, out);
    case 5:
      return SumFixed<5>(in, step, n, out);
    case 7:
      return SumFixed<7>(in, step, n, out);
    case 9:
      return SumFixed<9>(in, step, n, out);
    default:
      std::copy(in, in + n, out);
      for (int k = 1; k < count; ++k)
        for (int x = 0; x < n; ++x) out[x] += in[x + k * step];
  }
}

// One row of one view's correlation with keyframe 1, from the window sums m (4 channels of n
// values, as WindowSums gives them): where the view covers every pixel of the window that keyframe
// 1 covers, seen counts up; where both windows also have texture, sum gains the NCC and count one.
// Branch-free, so that it vectorises. window_inside: keyframe 1's coverage mean per window;
// mean_i, var_i: its grey level's.
GF_VECTOR_CLONES void AccumulateCorrelation(const float* m, int n, float inv_area, float min_inside,
                                            float min_var, const float* window_inside,
                                            const float* mean_i, const float* var_i,
                                            float* __restrict sum, float* __restrict count,
                                            float* __restrict seen) {
  const float *m_jc = m, *m_jj = m + n, *m_ji = m + 2 * n, *m_c = m + 3 * n;
  for (int x = 0; x < n; ++x) {
    const float inside_x = window_inside[x];
    const int inside = (inside_x >= min_inside) & (m_c[x] * inv_area >= inside_x - 1e-3f);
    const float inv_n = inv_area / inside_x;
    const float mj = m_jc[x] * inv_n;
    const float vj = m_jj[x] * inv_n - mj * mj;
    const int textured = inside & (vj > min_var) & (var_i[x] > min_var);
    const float ncc =
        (m_ji[x] * inv_n - mean_i[x] * mj) / std::sqrt(std::max(var_i[x] * vj, 1e-12f));
    seen[x] += static_cast<float>(inside);
    sum[x] += ncc * static_cast<float>(textured);
    count[x] += static_cast<float>(textured);
  }
}

// One row of the cost volume from the correlation sums of all views (sum, count, seen as
// AccumulateCorrelation leaves them; var_i: keyframe 1's window variance): textureless_cost where
// no view sees the window or keyframe 1's window is flat; 100 where it is textured and flat in
// every view (no match); else 100 (1 - mean NCC), plus 0.5 (so that truncation rounds). Branch-free
// (a clamp here would not vectorise: the caller clamps).
GF_VECTOR_CLONES void CostRow(const float* __restrict sum, const float* __restrict count,
                              const float* __restrict var_i, const float* __restrict seen, int n,
                              float min_var, float textureless_cost, float* __restrict out) {
  for (int x = 0; x < n; ++x) {
    // No textured view (count 0, so sum 0): 100. (A ternary: std::max would not vectorise.)
    const float views = count[x] < 1.f ? 1.f : count[x];
    const float matched = 100.f * (1.f - sum[x] / views);
    // A blend, not a select of `matched`: the compiler would move the division under the
    // condition, and a conditional division does not vectorise.
    const float seen_here = seen[x] > 0.f ? 1.f : 0.f;
    const float textured = var_i[x] > min_var ? seen_here : 0.f;
    const float value = textureless_cost + textured * (matched - textureless_cost);
    out[x] = value + 0.5f;  // truncated (and clamped) by the caller: rounded
  }
}

// Where the pixels (x, y), x < n, of a row map through the homography h (row-major): the
// homography is affine along a row up to the division. Behind the camera, or with a homography that
// is not finite: -1, outside every image.
GF_VECTOR_CLONES void SamplePositions(const float* h, bool finite, int y, int n,
                                      float* __restrict u, float* __restrict v) {
  const float bx = h[1] * y + h[2], by = h[4] * y + h[5], bz = h[7] * y + h[8];
  for (int x = 0; x < n; ++x) {
    const float qz = bz + h[6] * x;
    const bool ahead = qz > 1e-9f && finite;
    const float inv = ahead ? 1.f / qz : 0.f;
    u[x] = ahead ? (bx + h[0] * x) * inv : -1.f;
    v[x] = ahead ? (by + h[3] * x) * inv : -1.f;
  }
}

// One row of samples of a view at positions (u, v) (outside the image: none; never NaN, as
// SamplePositions gives them): J, bilinear where every pixel with a share in it lies in the view's
// image, else 0 and uncovered; then the products the window sums need, weighted by keyframe 1's
// coverage c1 (i1: its grey level). Branch-free, so that it vectorises (gathers).
GF_VECTOR_CLONES void SampleRow(const ViewData& view, const float* __restrict u_in,
                                const float* __restrict v_in, int n, const float* __restrict i1,
                                const float* __restrict c1, float* __restrict jc,
                                float* __restrict jj, float* __restrict ji,
                                float* __restrict covered) {
  const int width = view.gray.cols;
  // Largest positions whose 2x2 neighbourhood is inside: just below the last row and column.
  const float max_u = std::nextafter(static_cast<float>(width - 1), 0.f),
              max_v = std::nextafter(static_cast<float>(view.gray.rows - 1), 0.f);
  const float* gray = reinterpret_cast<const float*>(view.gray.data);
  for (int x = 0; x < n; ++x) {
    // Clamped into the image; inside when clamping changed nothing (two selects: a combined
    // condition would not vectorise).
    const float u = std::min(std::max(u_in[x], 0.f), max_u),
                v = std::min(std::max(v_in[x], 0.f), max_v);
    const float inside_u = u == u_in[x] ? 1.f : 0.f;
    const float inside = v == v_in[x] ? inside_u : 0.f;
    const int x0 = static_cast<int>(u), y0 = static_cast<int>(v);
    const int at = y0 * width + x0;
    const float fu = u - x0, fv = v - y0;
    const float top = gray[at] + fu * (gray[at + 1] - gray[at]);
    const float bottom = gray[at + width] + fu * (gray[at + width + 1] - gray[at + width]);
    const float sample = top + fv * (bottom - top);
    // Any uncovered pixel with a share in the sample drags it far below zero.
    const float seen = sample > -0.5f ? inside : 0.f;
    const float j = sample * seen;
    const float weighted = j * c1[x];
    jc[x] = weighted;
    jj[x] = weighted * j;
    ji[x] = weighted * i1[x];
    covered[x] = seen * c1[x];
  }
}

// The hole channels of a sampled row: the four channels (each `padded` apart) weighted by the
// hole share h of keyframe 1's coverage instead of the coverage c, which is 0 or 1: c h = h.
GF_VECTOR_CLONES void WeightByHoles(const float* __restrict h, int n, size_t padded,
                                    float* __restrict channels) {
  for (int c = 0; c < 4; ++c) {
    const float* in = channels + static_cast<size_t>(c) * padded;
    float* out = channels + static_cast<size_t>(c + 4) * padded;
    for (int x = 0; x < n; ++x) out[x] = in[x] * h[x];
  }
}

// Per pixel, the hole channels (4..7 of m) where use_hole is 1, else the full ones (0..3) (use_hole
// is 0 or 1): out holds 4 channels of n values. Arithmetic, so that it vectorises.
GF_VECTOR_CLONES void SelectWindows(const float* __restrict m, const float* __restrict use_hole,
                                    int n, float* __restrict out) {
  for (int c = 0; c < 4; ++c) {
    const float* full = m + static_cast<size_t>(c) * n;
    const float* hole = m + static_cast<size_t>(c + 4) * n;
    float* o = out + static_cast<size_t>(c) * n;
    for (int x = 0; x < n; ++x) o[x] = use_hole[x] * hole[x] + (1.f - use_hole[x]) * full[x];
  }
}

// sum[i] += sign * row[i] for i < n (vectorises).
GF_VECTOR_CLONES void Accumulate(const float* __restrict row, size_t n, float sign,
                                 float* __restrict sum) {
  for (size_t i = 0; i < n; ++i) sum[i] += sign * row[i];
}

// Window sums of one view's warped grey level J for a plane, one output row at a time: J is
// sampled bilinearly through the plane's homography (key1 pixel -> view pixel), then summed over
// window x window pixels (zero outside the ROI, as a constant-border box filter). The four sums:
// J c, J^2 c, J I c and the view's coverage c (c: keyframe 1's coverage, I: its grey level); with
// a hole weight h (keyframe 1's hole share of c, c being 0 or 1), four more with h in place of c,
// for windows that use hole pixels only. Rows are summed directly; columns by running sums that
// are redone directly every kExactEvery rows, so float rounding cannot drift.
class WindowSums {
 public:
  WindowSums(int rows, int cols, int window, bool holes)
      : rows_(rows),
        cols_(cols),
        window_(window),
        half_(window / 2),
        channels_(holes ? 8 : 4),
        padded_(cols + 2 * (window / 2)),
        sample_(static_cast<size_t>(channels_) * padded_, 0.f),
        ring_(static_cast<size_t>(window) * channels_ * cols, 0.f),
        sums_(static_cast<size_t>(channels_) * cols),
        u_(cols),
        v_(cols) {}

  // Runs over the ROI for one view and plane; calls row_done(y, sums) for every output row y,
  // sums holding the 4 (or 8, with holes) channels of `cols` values each (channel-major).
  // h_roi: the hole weights, used only when the object was made with holes.
  template <typename RowDone>
  void Run(const ViewData& view, const Eigen::Matrix3d& key1_to_view, const cv::Mat& i_roi,
           const cv::Mat& c_roi, const cv::Mat& h_roi, RowDone row_done) {
    std::fill(ring_.begin(), ring_.end(), 0.f);
    float h[9];
    for (int i = 0; i < 9; ++i) h[i] = static_cast<float>(key1_to_view(i / 3, i % 3));
    const bool finite = key1_to_view.allFinite();
    const size_t row_values = static_cast<size_t>(channels_) * cols_;
    std::fill(sums_.begin(), sums_.end(), 0.f);
    for (int y = 0; y < rows_ + half_; ++y) {
      // The slot of the row that leaves the window (zero for the first rows).
      float* slot = &ring_[static_cast<size_t>(y % window_) * row_values];
      const int out_row = y - half_;
      const bool exact = out_row % kExactEvery == 0;  // direct sums this row, else running ones
      if (!exact) Accumulate(slot, row_values, -1.f, sums_.data());
      if (y < rows_) {
        SamplePositions(h, finite, y, cols_, u_.data(), v_.data());
        float* jc = &sample_[half_];
        SampleRow(view, u_.data(), v_.data(), cols_, i_roi.ptr<float>(y), c_roi.ptr<float>(y), jc,
                  jc + padded_, jc + 2 * padded_, jc + 3 * padded_);
        if (channels_ == 8) WeightByHoles(h_roi.ptr<float>(y), cols_, padded_, jc);
        for (int c = 0; c < channels_; ++c)
          SumWindows(&sample_[static_cast<size_t>(c) * padded_], 1, window_, cols_,
                     slot + static_cast<size_t>(c) * cols_);
      } else {
        std::fill(slot, slot + row_values, 0.f);
      }
      // The ring holds rows out_row - half .. out_row + half (in rotated order).
      if (exact)
        SumWindows(ring_.data(), row_values, window_, static_cast<int>(row_values), sums_.data());
      else
        Accumulate(slot, row_values, 1.f, sums_.data());
      if (out_row < 0) continue;
      row_done(out_row, sums_.data());
    }
  }

 private:
  // Vertical sums run (add the row that enters, subtract the one that leaves) and are summed
  // directly every kExactEvery-th row, which bounds float drift to a few roundings.
  static constexpr int kExactEvery = 8;
  int rows_, cols_, window_, half_, channels_;
  size_t padded_;
  std::vector<float> sample_;  // the channels of one ROI row, padded by half a window each side
  std::vector<float> ring_;    // the last `window` rows' horizontal sums, all channels
  std::vector<float> sums_, u_, v_;
};

// Cost volume entries: 100 * (1 - mean NCC) in [0, 200]; textureless_cost where keyframe 1's
// window is flat or no view sees it (neutral: aggregation then carries the neighbours' evidence).

// One path of semi-global aggregation (Hirschmueller 2008) over cost[rows][cols][planes], added
// into sum: L(p, d) = C(p, d) + min(L(q, d), L(q, d +- 1) + p1, min_k L(q, k) + p2) - min_k L(q, k)
// with q the predecessor of p along (dx, dy). Rows are visited in the path's vertical direction,
// so a predecessor is either earlier in the same row (dy = 0) or in the previous row.
GF_VECTOR_CLONES void AggregatePath(const std::vector<uint8_t>& cost, int rows, int cols,
                                    int planes, int dx, int dy, int p1, int p2,
                                    std::vector<uint16_t>* sum) {
  // Each pixel's L row is padded with one large entry on either side, so that the d - 1 and
  // d + 1 neighbours need no bounds checks (and the loop vectorises).
  const size_t stride = static_cast<size_t>(planes) + 2;
  constexpr uint16_t kPad = 0x3fff;
  std::vector<uint16_t> previous(cols * stride, kPad), current(cols * stride, kPad);
  std::vector<uint16_t> previous_min(cols), current_min(cols);
  for (int i = 0; i < rows; ++i) {
    const int y = dy >= 0 ? i : rows - 1 - i;
    for (int j = 0; j < cols; ++j) {
      const int x = dx >= 0 ? j : cols - 1 - j;
      const uint8_t* __restrict c = &cost[(static_cast<size_t>(y) * cols + x) * planes];
      uint16_t* __restrict l = &current[x * stride + 1];
      uint16_t* __restrict s = &(*sum)[(static_cast<size_t>(y) * cols + x) * planes];
      const int px = x - dx, py = y - dy;
      uint16_t lowest = kPad;
      if (px < 0 || px >= cols || py < 0 || py >= rows) {
        for (int d = 0; d < planes; ++d) l[d] = c[d];
      } else {
        const uint16_t* __restrict q =
            dy == 0 ? &current[px * stride + 1] : &previous[px * stride + 1];
        const uint16_t q_min = dy == 0 ? current_min[px] : previous_min[px];
        const uint16_t jump = static_cast<uint16_t>(q_min + p2), small = static_cast<uint16_t>(p1);
        for (int d = 0; d < planes; ++d) {
          uint16_t v = std::min(q[d], jump);
          v = std::min(v, static_cast<uint16_t>(std::min(q[d - 1], q[d + 1]) + small));
          l[d] = static_cast<uint16_t>(c[d] + v - q_min);
        }
      }
      for (int d = 0; d < planes; ++d) {
        lowest = std::min(lowest, l[d]);
        s[d] = static_cast<uint16_t>(s[d] + l[d]);
      }
      current_min[x] = lowest;
    }
    std::swap(previous, current);
    std::swap(previous_min, current_min);
  }
}

}  // namespace

bool PlaneSweepOptions::Check(std::string* message) const {
  if (window_px < 3 || window_px % 2 == 0 || max_planes < 3 || max_planes > 250 ||
      !(max_step_px > 0) || !(min_ncc > -1 && min_ncc < 1) ||
      !(min_uniqueness >= 0 && min_uniqueness < 1) || !(min_parallax_px >= 0) ||
      !(min_texture >= 0) || !(min_window_inside > 0 && min_window_inside <= 1) ||
      smooth_small < 0 || smooth_large < smooth_small || smooth_large > 1000 ||
      textureless_cost < 0 || textureless_cost > 200 || downscale < 1 || downscale > 4) {
    if (message)
      *message =
          "plane sweep: odd window >= 3, 3..250 planes, thresholds in range, 0 <= smooth_small <= "
          "smooth_large <= 1000, textureless_cost in [0, 200], downscale 1..4";
    return false;
  }
  return true;
}

std::string PlaneSweepResult::BriefReport() const {
  char buffer[160];
  std::snprintf(buffer, sizeof(buffer), "plane sweep: %d planes, %d of %d pixels accepted", planes,
                accepted_pixels, requested_pixels);
  return buffer;
}

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

  // Undistort everything once; from here on the camera is the pinhole K.
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
  // Box filters keep running sums, so a NaN would poison whole rows: pixels outside an image are
  // 0 and tracked by a coverage image instead. Correlation windows are weighted by keyframe 1's
  // coverage, so windows that cross its image border use the part inside. The sweep runs on
  // images shrunk by `downscale` (area averaging) with the camera matrix scaled to match.
  const double scale = 1.0 / options.downscale;
  const Camera work_camera = camera.Scaled(scale);  // the working images' pinhole camera
  const cv::Size work(work_camera.width, work_camera.height);
  const cv::Mat ones(size, CV_32F, cv::Scalar(1.f));
  const cv::Mat cover_full = undistort(ones, cv::INTER_NEAREST);
  cv::Mat cover1;
  cv::resize(cover_full, cover1, work, 0, 0, cv::INTER_AREA);
  // Grey levels at working size: the mean over the covered part of each cell, 0 outside.
  auto shrink_gray = [&](const cv::Mat& bgr) {
    cv::Mat gray = undistort(GrayFloat(bgr), cv::INTER_LINEAR).mul(cover_full), out;
    cv::resize(gray, out, work, 0, 0, cv::INTER_AREA);
    cv::divide(out, cv::max(cover1, 1e-6), out);
    return out;
  };
  cv::threshold(cover1, cover1, 0.99, 1.0, cv::THRESH_BINARY);
  const cv::Mat gray1 = shrink_gray(key1.color).mul(cover1);
  cv::Mat region_full = undistort(mask, cv::INTER_NEAREST), region;
  region_full.convertTo(region_full, CV_32F);
  cv::resize(region_full, region, work, 0, 0, cv::INTER_AREA);
  region = region > 0;  // a working pixel is wanted when any of its pixels is
  cv::dilate(region, region, cv::Mat());
  std::vector<ViewData> data;
  double max_baseline = 0;
  for (const SweepView& v : views) {
    GF_CHECK(v.frame != nullptr && v.frame->color.type() == CV_8UC3, "views need BGR colour");
    const SE3 view_from_key1 = v.key1_from_view.Inverse();
    cv::Mat gray = shrink_gray(v.frame->color);
    gray.setTo(kUncovered, cover1 == 0.f);
    data.push_back({gray, view_from_key1.RotationMatrix(), view_from_key1.translation()});
    max_baseline = std::max(max_baseline, view_from_key1.TranslationNorm());
  }
  const Eigen::Matrix3d k = work_camera.K(), k_inv = k.inverse();

  // Work on the bounding box of the region, widened by the window.
  const int half = options.window_px / 2;
  cv::Rect roi = cv::boundingRect(region);
  roi.x -= half + 1;
  roi.y -= half + 1;
  roi.width += 2 * half + 2;
  roi.height += 2 * half + 2;
  roi &= cv::Rect(0, 0, work.width, work.height);
  const cv::Size box(options.window_px, options.window_px);
  const cv::Mat i_roi = gray1(roi), c_roi = cover1(roi);
  // Keyframe 1's window statistics for window weights w: the weighted share of the window (n1),
  // mean and variance of its grey level.
  auto window_statistics = [&](const cv::Mat& w, cv::Mat* n1, cv::Mat* mean, cv::Mat* var) {
    const cv::Mat iw = i_roi.mul(w);
    cv::boxFilter(w, *n1, CV_32F, box, cv::Point(-1, -1), true, cv::BORDER_CONSTANT);
    cv::boxFilter(iw, *mean, CV_32F, box, cv::Point(-1, -1), true, cv::BORDER_CONSTANT);
    cv::boxFilter(iw.mul(i_roi), *var, CV_32F, box, cv::Point(-1, -1), true, cv::BORDER_CONSTANT);
    cv::max(*n1, 1e-6, *n1);
    cv::divide(*mean, *n1, *mean);
    cv::divide(*var, *n1, *var);
    *var -= mean->mul(*mean);
  };
  cv::Mat n1, mean_i, var_i;  // weighted by keyframe 1's coverage
  window_statistics(c_roi, &n1, &mean_i, &var_i);
  // Hole windows: a hole pixel's window uses the hole pixels only (weights h_roi, keyframe 1's
  // hole share of its coverage), where they fill at least min_window_inside of it; its statistics
  // replace the full window's there (use_hole 1). Projector-shadow pixels are left out of them:
  // they show the background beside a foreground's edge, which a no-return surface's window
  // (clear glass beside the shadow it casts) would otherwise match at that edge's depth.
  cv::Mat h_roi, use_hole;
  if (options.hole_windows) {
    const cv::Mat own_holes =
        (key1.hole_mask != 0) & (key1.hole_mask != static_cast<uint8_t>(HoleCode::kShadow));
    cv::Mat holes_full = undistort(own_holes, cv::INTER_NEAREST), holes;
    holes_full.convertTo(holes_full, CV_32F, 1.0 / 255);
    cv::resize(holes_full, holes, work, 0, 0, cv::INTER_AREA);
    h_roi = holes(roi).mul(c_roi);
    cv::Mat n1_hole, mean_hole, var_hole;
    window_statistics(h_roi, &n1_hole, &mean_hole, &var_hole);
    const cv::Mat selected = (h_roi >= 0.5f) & (n1_hole >= options.min_window_inside);
    if (cv::countNonZero(selected) > 0) {
      selected.convertTo(use_hole, CV_32F, 1.0 / 255);
      n1_hole.copyTo(n1, selected);
      mean_hole.copyTo(mean_i, selected);
      var_hole.copyTo(var_i, selected);
    }
  }
  const bool hole_windows = !use_hole.empty();
  const double min_var = options.min_texture * options.min_texture;

  // Planes evenly spaced in inverse depth, close enough that no pixel jumps more than max_step_px.
  const double f = std::max(k(0, 0), k(1, 1));
  const double w_near = 1.0 / min_depth_m, w_far = 1.0 / max_depth_m;
  const double step_needed = options.max_step_px / (1.5 * f * std::max(max_baseline, 1e-6));
  result.planes = std::clamp(static_cast<int>(std::ceil((w_near - w_far) / step_needed)) + 1, 3,
                             options.max_planes);
  const int planes = result.planes;
  const double dw = (w_near - w_far) / (planes - 1);

  const int rows = roi.height, cols = roi.width;
  const size_t pixels = static_cast<size_t>(rows) * cols;
  std::vector<uint8_t> cost(pixels * planes);
  Eigen::Matrix3d shift = Eigen::Matrix3d::Identity();  // ROI pixel -> full image pixel
  shift(0, 2) = roi.x;
  shift(1, 2) = roi.y;
  cv::Mat sum(rows, cols, CV_32F), count(rows, cols, CV_32F), seen(rows, cols, CV_32F);
  WindowSums window_sums(rows, cols, options.window_px, hole_windows);
  std::vector<float> selected(hole_windows ? 4 * cols : 0);
  const float inv_area = 1.f / (options.window_px * options.window_px);
  const float min_var_f = static_cast<float>(min_var);
  const float min_inside = static_cast<float>(options.min_window_inside);
  const float neutral = static_cast<float>(options.textureless_cost);
  // Costs are written plane-major for a block of planes, then moved into the pixel-major volume
  // a block at a time (contiguous bytes per pixel instead of one scattered byte per plane).
  constexpr int kBlock = 16;
  std::vector<uint8_t> block(static_cast<size_t>(kBlock) * pixels);
  std::vector<float> row_cost(cols);
  auto flush_block = [&](int first_plane, int count_planes) {
    for (size_t p = 0; p < pixels; ++p) {
      uint8_t* out = &cost[p * planes + first_plane];
      for (int b = 0; b < count_planes; ++b) out[b] = block[b * pixels + p];
    }
  };
  for (int plane = 0; plane < planes; ++plane) {
    const double w = w_far + plane * dw;
    sum.setTo(0.f);
    count.setTo(0.f);
    seen.setTo(0.f);
    for (const ViewData& v : data) {
      Eigen::Matrix3d h = v.rotation;
      h.col(2) += v.translation * w;  // R + t n^T / z with n = (0, 0, 1)
      // Correlation over keyframe 1's covered pixels of each window.
      window_sums.Run(v, k * h * k_inv * shift, i_roi, c_roi, h_roi, [&](int y, const float* m) {
        if (hole_windows) {
          SelectWindows(m, use_hole.ptr<float>(y), cols, selected.data());
          m = selected.data();
        }
        AccumulateCorrelation(m, cols, inv_area, min_inside, min_var_f, n1.ptr<float>(y),
                              mean_i.ptr<float>(y), var_i.ptr<float>(y), sum.ptr<float>(y),
                              count.ptr<float>(y), seen.ptr<float>(y));
      });
    }
    uint8_t* plane_cost = &block[static_cast<size_t>(plane % kBlock) * pixels];
    for (int y = 0; y < rows; ++y) {
      CostRow(sum.ptr<float>(y), count.ptr<float>(y), var_i.ptr<float>(y), seen.ptr<float>(y), cols,
              min_var_f, neutral, row_cost.data());
      uint8_t* out = plane_cost + static_cast<size_t>(y) * cols;
      for (int x = 0; x < cols; ++x)
        out[x] = static_cast<uint8_t>(std::clamp(static_cast<int>(row_cost[x]), 0, 200));
    }
    if (plane % kBlock == kBlock - 1 || plane == planes - 1)
      flush_block(plane - plane % kBlock, plane % kBlock + 1);
  }

  // Aggregation along 8 paths (or none), then the best plane per pixel.
  const bool smooth = options.smooth_large > 0;
  std::vector<uint16_t> total;
  if (smooth) {
    total.assign(pixels * planes, 0);
    for (const auto& [dx, dy] : std::vector<std::pair<int, int>>{
             {1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {-1, 1}, {1, -1}, {-1, -1}})
      AggregatePath(cost, rows, cols, planes, dx, dy, options.smooth_small, options.smooth_large,
                    &total);
  } else {
    total.assign(cost.begin(), cost.end());
  }

  // Accept, refine, and write back into keyframe 1's (distorted) pixel grid.
  cv::Mat depth_u(work, CV_32F, cv::Scalar(0.f)), score_u(work, CV_32F, cv::Scalar(0.f));
  const double min_parallax = options.min_parallax_px * scale;  // working pixels
  for (int y = 0; y < rows; ++y) {
    const uint8_t* r = region.ptr<uint8_t>(y + roi.y) + roi.x;
    const float* vi = var_i.ptr<float>(y);
    for (int x = 0; x < cols; ++x) {
      if (!r[x]) continue;
      const size_t base = (static_cast<size_t>(y) * cols + x) * planes;
      const uint16_t* t = &total[base];
      const int bk = static_cast<int>(std::min_element(t, t + planes) - t);
      const uint8_t c = cost[base + bk];
      // Flat windows carry no evidence of their own; aggregation would only copy a neighbour's
      // depth into them (across occlusion edges too), so they get none.
      if (!(vi[x] > min_var) || c > 100.0 * (1.0 - options.min_ncc)) continue;
      int others = std::numeric_limits<int>::max();
      for (int d = 0; d < planes; ++d)
        if (std::abs(d - bk) > 1) others = std::min<int>(others, t[d]);
      if (t[bk] > (1.0 - options.min_uniqueness) * others) continue;
      double offset = 0;
      if (bk > 0 && bk + 1 < planes) {
        const double l = t[bk - 1], b = t[bk], rt = t[bk + 1];
        const double denominator = l - 2.0 * b + rt;
        if (denominator > 0) offset = std::clamp(0.5 * (l - rt) / denominator, -0.5, 0.5);
      }
      const double z = 1.0 / (w_far + (bk + offset) * dw);
      // Parallax: how far a 3% depth change moves the pixel in the best-placed view.
      const Eigen::Vector3d ray = k_inv * Eigen::Vector3d(x + roi.x, y + roi.y, 1.0);
      // Only views that see the point count (a pixel no view sees has no depth).
      double parallax = 0;
      for (const ViewData& v : data) {
        const Eigen::Vector3d a = v.rotation * ray * z + v.translation;
        const Eigen::Vector3d b3 = v.rotation * ray * (1.03 * z) + v.translation;
        if (a.z() <= 0 || b3.z() <= 0) continue;
        const Eigen::Vector2d pa = (k * a).hnormalized(), pb = (k * b3).hnormalized();
        if (pa.x() < 0 || pa.y() < 0 || pa.x() > work.width - 1 || pa.y() > work.height - 1)
          continue;
        parallax = std::max(parallax, (pa - pb).norm());
      }
      if (parallax < min_parallax) continue;
      depth_u.at<float>(y + roi.y, x + roi.x) = static_cast<float>(z);
      score_u.at<float>(y + roi.y, x + roi.x) = 1.f - c / 100.f;
    }
  }
  const UndistortedPixels undistorted(camera);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      if (!mask.at<uint8_t>(y, x)) continue;
      const Eigen::Vector2d u = undistorted.At(x, y);  // full size
      const int ux = static_cast<int>(std::lround((u.x() + 0.5) * scale - 0.5)),
                uy = static_cast<int>(std::lround((u.y() + 0.5) * scale - 0.5));
      if (ux < 0 || uy < 0 || ux >= work.width || uy >= work.height) continue;
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
