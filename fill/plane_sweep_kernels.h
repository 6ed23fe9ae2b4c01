// The inner loops of the plane sweep (fill/plane_sweep.h): warping a view through a plane's
// homography fused with window sums, the correlation and cost of a row, and semi-global
// aggregation. Internal to plane_sweep.cc (and plane_sweep_kernels_test.cc, which alone include
// it): written as branch-free loops over rows so that they vectorise, and compiled for AVX2 and
// baseline x86-64.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace gf::sweep_detail {

// The inner loops are compiled twice, for AVX2 (twice the vector width) and for the baseline
// x86-64 (SSE2); the loader picks what the CPU has. Not under ThreadSanitizer: the loader runs the
// clones' resolver before the sanitizer's runtime exists, and its instrumented code crashes.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_THREAD__)
#define GF_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define GF_VECTOR_CLONES
#endif

// Helpers of those loops, inlined into them wherever they are called (so that the clones
// vectorise them), whatever GCC's inlining heuristics think of their size.
#if defined(__GNUC__)
#define GF_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define GF_ALWAYS_INLINE inline
#endif

inline cv::Mat GrayFloat(const cv::Mat& bgr) {
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
inline void SumFixed(const float* __restrict in, size_t step, int n, float* __restrict out) {
  for (int x = 0; x < n; ++x) {
    float a = in[x];
    for (int k = 1; k < kCount; ++k) a += in[x + k * step];
    out[x] = a;
  }
}
GF_VECTOR_CLONES inline void SumWindows(const float* in, size_t step, int count, int n,
                                        float* out) {
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

// One pixel's correlation of one view with keyframe 1 from its window sums (m_jc, m_jj, m_ji, m_c
// as WindowSums gives them): where the view covers every pixel of the window that keyframe 1
// covers, seen counts up; where both windows also have texture, sum gains the NCC and count one.
// Branch-free, so that the loops calling it vectorise. inside_x: keyframe 1's coverage mean of the
// window; inv_n: inv_area / inside_x (the same for every plane, so computed once); mean_i, var_i:
// its grey level's. kFirst: the first view writes the three outputs instead of adding to them.
template <bool kFirst>
GF_ALWAYS_INLINE void CorrelationStep(float m_jc, float m_jj, float m_ji, float m_c, float inv_area,
                                      float min_inside, float min_var, float inside_x, float inv_n,
                                      float mean_i, float var_i, float* sum, float* count,
                                      float* seen) {
  const int inside = (inside_x >= min_inside) & (m_c * inv_area >= inside_x - 1e-3f);
  const float mj = m_jc * inv_n;
  const float vj = m_jj * inv_n - mj * mj;
  const int textured = inside & (vj > min_var) & (var_i > min_var);
  const float ncc = (m_ji * inv_n - mean_i * mj) / std::sqrt(std::max(var_i * vj, 1e-12f));
  if constexpr (kFirst) {
    *seen = static_cast<float>(inside);
    *sum = ncc * static_cast<float>(textured);
    *count = static_cast<float>(textured);
  } else {
    *seen += static_cast<float>(inside);
    *sum += ncc * static_cast<float>(textured);
    *count += static_cast<float>(textured);
  }
}

// Keyframe 1's window statistics along one row of the ROI, the same for every plane and view.
struct KeyframeRow {
  const float* inside;    // coverage mean of each window
  const float* inv_n;     // inv_area / inside
  const float* mean;      // grey level mean
  const float* var;       // grey level variance
  const float* use_hole;  // 1 where the pixel's window uses hole pixels only, else 0; null: none
};

// One row of one view's correlation with keyframe 1 (CorrelationStep per pixel) at columns
// [begin, end) from the window sums m (4 channels of n values; with k.use_hole, 8: the full
// windows' then the hole windows'), taking the hole windows' sums where use_hole is 1 (a blend, so
// that it vectorises).
template <bool kFirst>
GF_ALWAYS_INLINE void CorrelationRow(const float* m, const KeyframeRow& k, int n, int begin,
                                     int end, float inv_area, float min_inside, float min_var,
                                     float* __restrict sum, float* __restrict count,
                                     float* __restrict seen) {
  const float *m_jc = m, *m_jj = m + n, *m_ji = m + 2 * n, *m_c = m + 3 * n;
  const float *inside = k.inside, *inv_n = k.inv_n, *mean = k.mean, *var = k.var;
  if (k.use_hole == nullptr) {
    for (int x = begin; x < end; ++x)
      CorrelationStep<kFirst>(m_jc[x], m_jj[x], m_ji[x], m_c[x], inv_area, min_inside, min_var,
                              inside[x], inv_n[x], mean[x], var[x], &sum[x], &count[x], &seen[x]);
    return;
  }
  const float *h_jc = m + 4 * n, *h_jj = m + 5 * n, *h_ji = m + 6 * n, *h_c = m + 7 * n;
  const float* use_hole = k.use_hole;
  for (int x = begin; x < end; ++x) {
    const float a = use_hole[x], b = 1.f - use_hole[x];
    CorrelationStep<kFirst>(a * h_jc[x] + b * m_jc[x], a * h_jj[x] + b * m_jj[x],
                            a * h_ji[x] + b * m_ji[x], a * h_c[x] + b * m_c[x], inv_area,
                            min_inside, min_var, inside[x], inv_n[x], mean[x], var[x], &sum[x],
                            &count[x], &seen[x]);
  }
}

// CorrelationRow for one view: the first view of a plane (first) writes sum, count and seen, the
// others add to them.
GF_VECTOR_CLONES inline void AccumulateCorrelation(const float* m, const KeyframeRow& k, int n,
                                                   int begin, int end, float inv_area,
                                                   float min_inside, float min_var, bool first,
                                                   float* __restrict sum, float* __restrict count,
                                                   float* __restrict seen) {
  if (first)
    CorrelationRow<true>(m, k, n, begin, end, inv_area, min_inside, min_var, sum, count, seen);
  else
    CorrelationRow<false>(m, k, n, begin, end, inv_area, min_inside, min_var, sum, count, seen);
}

// Columns [begin, end) of a row of the cost volume from the correlation sums of all views (sum,
// count, seen as AccumulateCorrelation leaves them; var_i: keyframe 1's window variance):
// textureless_cost where no view sees the window or keyframe 1's window is flat; 100 where it is
// textured and flat in every view (no match); else 100 (1 - mean NCC), plus 0.5 (so that
// truncation rounds). Branch-free (a clamp here would not vectorise: the caller clamps).
GF_VECTOR_CLONES inline void CostRow(const float* __restrict sum, const float* __restrict count,
                                     const float* __restrict var_i, const float* __restrict seen,
                                     int begin, int end, float min_var, float textureless_cost,
                                     float* __restrict out) {
  for (int x = begin; x < end; ++x) {
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
GF_VECTOR_CLONES inline void SamplePositions(const float* h, bool finite, int y, int n,
                                             float* __restrict u, float* __restrict v) {
  if (!finite) {
    std::fill(u, u + n, -1.f);
    std::fill(v, v + n, -1.f);
    return;
  }
  const float bx = h[1] * y + h[2], by = h[4] * y + h[5], bz = h[7] * y + h[8];
  const float ax = h[0], ay = h[3], az = h[6];
  // Every pixel divides, with no condition, so that the loop vectorises (a comparison in it would
  // not, under IEEE trapping rules); pixels behind the camera are overwritten below.
  for (int x = 0; x < n; ++x) {
    const float inv = 1.f / (bz + az * x);
    u[x] = (bx + ax * x) * inv;
    v[x] = (by + ay * x) * inv;
  }
  // The depth bz + az x is monotonic in x (float rounding keeps that), so the pixels behind the
  // camera lie at one end of the row: mark them from that end.
  const auto behind = [&](int x) { return !(bz + az * x > 1e-9f); };
  if (az >= 0.f) {
    for (int x = 0; x < n && behind(x); ++x) u[x] = v[x] = -1.f;
  } else {
    for (int x = n - 1; x >= 0 && behind(x); --x) u[x] = v[x] = -1.f;
  }
}

// One row of samples of a view at positions (u, v) (outside the image: none; never NaN, as
// SamplePositions gives them): J, bilinear where every pixel with a share in it lies in the view's
// image, else 0 and uncovered; then the products the window sums need, weighted by keyframe 1's
// coverage c1 (i1: its grey level). Branch-free, so that it vectorises (gathers).
GF_VECTOR_CLONES inline void SampleRow(const ViewData& view, const float* __restrict u_in,
                                       const float* __restrict v_in, int n,
                                       const float* __restrict i1, const float* __restrict c1,
                                       float* __restrict jc, float* __restrict jj,
                                       float* __restrict ji, float* __restrict covered) {
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
GF_VECTOR_CLONES inline void WeightByHoles(const float* __restrict h, int n, size_t padded,
                                           float* __restrict channels) {
  for (int c = 0; c < 4; ++c) {
    const float* in = channels + static_cast<size_t>(c) * padded;
    float* out = channels + static_cast<size_t>(c + 4) * padded;
    for (int x = 0; x < n; ++x) out[x] = in[x] * h[x];
  }
}

// Running window sums move down a row: sum[i] = sum[i] - leaving[i] + entering[i], then the
// entering row takes the leaving one's place in the ring (vectorises).
GF_VECTOR_CLONES inline void Slide(const float* __restrict entering, int n,
                                   float* __restrict leaving, float* __restrict sum) {
  for (int i = 0; i < n; ++i) {
    sum[i] = sum[i] - leaving[i] + entering[i];
    leaving[i] = entering[i];
  }
}

// Column ranges [begin, end) of a row.
struct Span {
  int begin, end;
};
using Spans = std::vector<Span>;

// The spans of a row's non-zero bytes (n of them), joining spans less than min_gap apart (one loop
// over a few unused columns costs less than starting another).
Spans SpansOf(const uint8_t* row, int n, int min_gap);

// Where the window sums are needed, for an `active` mask (CV_8U, the ROI's size) of the pixels
// whose costs are wanted: output rows come in blocks of kBlockRows (the running sums restart
// exactly at each block), and a block's spans cover the columns active in any of its rows; each
// row's horizontal sums are computed on the columns of every block whose windows reach it, and
// its samples half a window wider.
struct ActiveColumns {
  static constexpr int kBlockRows = 8;
  std::vector<Spans> block;   // per block of output rows
  std::vector<Spans> sums;    // per ROI row: columns of its horizontal window sums
  std::vector<Spans> sample;  // per ROI row: columns sampled
  // Per ROI row y: the columns of its horizontal sums outside the block of output row y - half
  // (the row it enters the window of), which Slide does not move into the ring.
  std::vector<Spans> carried;
  ActiveColumns(const cv::Mat& active, int half);
};

// Window sums of one view's warped grey level J for a plane, one output row at a time: J is
// sampled bilinearly through the plane's homography (key1 pixel -> view pixel), then summed over
// window x window pixels (zero outside the ROI, as a constant-border box filter). The four sums:
// J c, J^2 c, J I c and the view's coverage c (c: keyframe 1's coverage, I: its grey level); with
// a hole weight h (keyframe 1's hole share of c, c being 0 or 1), four more with h in place of c,
// for windows that use hole pixels only. Rows are summed directly; columns by running sums that
// are redone directly at every block of ActiveColumns::kBlockRows rows, so float rounding cannot
// drift. Only the columns ActiveColumns names are computed; the others hold stale values.
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
        entering_(static_cast<size_t>(channels_) * cols),
        sums_(static_cast<size_t>(channels_) * cols, 0.f),
        u_(cols),
        v_(cols) {}

  // Runs over the ROI for one view and plane; calls row_done(y, sums, spans) for every output
  // row y, sums holding the 4 (or 8, with holes) channels of `cols` values each (channel-major),
  // valid in the columns `spans` names. h_roi: the hole weights, used only when the object was
  // made with holes.
  template <typename RowDone>
  void Run(const ViewData& view, const Eigen::Matrix3d& key1_to_view, const cv::Mat& i_roi,
           const cv::Mat& c_roi, const cv::Mat& h_roi, const ActiveColumns& active,
           RowDone row_done) {
    std::fill(ring_.begin(), ring_.end(), 0.f);
    float h[9];
    for (int i = 0; i < 9; ++i) h[i] = static_cast<float>(key1_to_view(i / 3, i % 3));
    const bool finite = key1_to_view.allFinite();
    const size_t row_values = static_cast<size_t>(channels_) * cols_;
    // Each channel's part of a row of `cols` values, over spans.
    auto for_spans = [&](const Spans& spans, auto f) {
      for (int c = 0; c < channels_; ++c)
        for (const Span& s : spans) f(static_cast<size_t>(c) * cols_ + s.begin, s.end - s.begin);
    };
    for (int y = 0; y < rows_ + half_; ++y) {
      // The slot of the row that leaves the window (zero for the first rows); the entering row
      // takes its place.
      float* slot = &ring_[static_cast<size_t>(y % window_) * row_values];
      const int out_row = y - half_;
      const Spans* spans =
          out_row >= 0 ? &active.block[out_row / ActiveColumns::kBlockRows] : nullptr;
      // Direct sums at a block's first row, else running ones. The entering row's horizontal
      // sums go straight into the ring, except for running sums: beside it, until Slide has
      // subtracted the leaving row.
      const bool running = spans && out_row % ActiveColumns::kBlockRows != 0;
      float* entering = running ? entering_.data() : slot;
      if (y < rows_) {
        SamplePositions(h, finite, y, cols_, u_.data(), v_.data());
        float* jc = &sample_[half_];
        for (const Span& s : active.sample[y]) {
          const int b = s.begin, n = s.end - s.begin;
          SampleRow(view, u_.data() + b, v_.data() + b, n, i_roi.ptr<float>(y) + b,
                    c_roi.ptr<float>(y) + b, jc + b, jc + padded_ + b, jc + 2 * padded_ + b,
                    jc + 3 * padded_ + b);
          if (channels_ == 8) WeightByHoles(h_roi.ptr<float>(y) + b, n, padded_, jc + b);
        }
        for (int c = 0; c < channels_; ++c)
          for (const Span& s : active.sums[y])
            SumWindows(&sample_[static_cast<size_t>(c) * padded_ + s.begin], 1, window_,
                       s.end - s.begin, entering + static_cast<size_t>(c) * cols_ + s.begin);
      } else {
        std::fill(entering, entering + row_values, 0.f);
      }
      if (!spans) continue;
      // The ring holds rows out_row - half .. out_row + half (in rotated order).
      if (!running) {
        for_spans(*spans, [&](size_t at, int n) {
          SumWindows(ring_.data() + at, row_values, window_, n, &sums_[at]);
        });
      } else {
        for_spans(*spans,
                  [&](size_t at, int n) { Slide(entering + at, n, slot + at, &sums_[at]); });
        if (y < rows_)
          for_spans(active.carried[y], [&](size_t at, int n) {
            std::copy(entering + at, entering + at + n, slot + at);
          });
        else
          std::fill(slot, slot + row_values, 0.f);
      }
      row_done(out_row, sums_.data(), *spans);
    }
  }

 private:
  int rows_, cols_, window_, half_, channels_;
  size_t padded_;
  std::vector<float> sample_;    // the channels of one ROI row, padded by half a window each side
  std::vector<float> ring_;      // the last `window` rows' horizontal sums, all channels
  std::vector<float> entering_;  // the entering row's horizontal sums (running sums)
  std::vector<float> sums_, u_, v_;
};

// Cost volume entries: 100 * (1 - mean NCC) in [0, 200]; textureless_cost where keyframe 1's
// window is flat or no view sees it (neutral: aggregation then carries the neighbours' evidence).

// One step of semi-global aggregation (Hirschmueller 2008) along a path, at pixel p with matching
// costs c: L(p, d) = C(p, d) + min(L(q, d), L(q, d +- 1) + p1, min_k L(q, k) + p2) - min_k L(q, k),
// q being p's predecessor on the path (its L in q, padded with one large entry on either side so
// that d - 1 and d + 1 need no bounds checks; null at the path's start: L = C). Writes L(p, .)
// to l and returns its minimum.
GF_ALWAYS_INLINE uint16_t PathStep(const uint8_t* __restrict c, const uint16_t* __restrict q,
                                   uint16_t q_min, int planes, int p1, int p2,
                                   uint16_t* __restrict l) {
  uint16_t lowest = 0xffff;
  if (q == nullptr) {
    for (int d = 0; d < planes; ++d) {
      l[d] = c[d];
      lowest = std::min(lowest, l[d]);
    }
    return lowest;
  }
  const uint16_t jump = static_cast<uint16_t>(q_min + p2), small = static_cast<uint16_t>(p1);
  for (int d = 0; d < planes; ++d) {
    uint16_t v = std::min(q[d], jump);
    v = std::min(v, static_cast<uint16_t>(std::min(q[d - 1], q[d + 1]) + small));
    l[d] = static_cast<uint16_t>(c[d] + v - q_min);
    lowest = std::min(lowest, l[d]);
  }
  return lowest;
}

// sum[d] = (add ? sum[d] : 0) + a[d] + b[d] + e[d] + f[d] for d < n (vectorises; wraps as uint16
// does).
GF_ALWAYS_INLINE void AddFour(const uint16_t* __restrict a, const uint16_t* __restrict b,
                              const uint16_t* __restrict e, const uint16_t* __restrict f, int n,
                              bool add, uint16_t* __restrict sum) {
  if (add) {
    for (int d = 0; d < n; ++d) sum[d] = static_cast<uint16_t>(sum[d] + a[d] + b[d] + e[d] + f[d]);
  } else {
    for (int d = 0; d < n; ++d) sum[d] = static_cast<uint16_t>(a[d] + b[d] + e[d] + f[d]);
  }
}

// Half of semi-global aggregation over cost[rows][cols][planes] into sum: the four paths whose
// predecessors come before each pixel in one scan of the image. Forward (rows top to bottom, each
// left to right): paths (dx, dy) = (1, 0), (0, 1), (1, 1), (-1, 1), written into sum; backward: the
// opposite four, added to it. The two passes give the 8 paths while reading the cost volume twice
// and accessing the sums three times (8 and 16 times, one path at a time).
GF_VECTOR_CLONES inline void AggregatePass(const uint8_t* cost, int rows, int cols, int planes,
                                           bool forward, int p1, int p2, uint16_t* sum) {
  const size_t stride = static_cast<size_t>(planes) + 2;
  constexpr uint16_t kPad = 0x3fff;
  // Per pixel of a row, the L of the three paths that come from the previous row (straight down
  // the columns, and the two diagonals), for the previous row and the current one; and the L of
  // the path along the row at the previous pixel and the current one. Pads stay at kPad.
  const size_t row_values = 3 * static_cast<size_t>(cols) * stride;
  std::vector<uint16_t> previous(row_values, kPad), current(row_values, kPad);
  std::vector<uint16_t> previous_min(3 * static_cast<size_t>(cols)), current_min(previous_min);
  std::vector<uint16_t> along(2 * stride, kPad);
  const int s = forward ? 1 : -1;
  auto at = [&](std::vector<uint16_t>& rows_l, int path, int x) {
    return &rows_l[(static_cast<size_t>(x) * 3 + path) * stride + 1];
  };
  for (int i = 0; i < rows; ++i) {
    const int y = forward ? i : rows - 1 - i;
    uint16_t along_min = 0;
    for (int j = 0; j < cols; ++j) {
      const int x = forward ? j : cols - 1 - j;
      const size_t p = static_cast<size_t>(y) * cols + x;
      const uint8_t* c = &cost[p * planes];
      uint16_t* l_along = &along[(j % 2) * stride + 1];
      const uint16_t* q_along = j > 0 ? &along[((j + 1) % 2) * stride + 1] : nullptr;
      along_min = PathStep(c, q_along, along_min, planes, p1, p2, l_along);
      // From the previous row: straight (path 0), from x - s (path 1) and from x + s (path 2).
      for (int path = 0; path < 3; ++path) {
        const int qx = x - s * (path == 1) + s * (path == 2);
        const bool has = i > 0 && qx >= 0 && qx < cols;
        const uint16_t q_min = has ? previous_min[static_cast<size_t>(qx) * 3 + path] : 0;
        current_min[static_cast<size_t>(x) * 3 + path] = PathStep(
            c, has ? at(previous, path, qx) : nullptr, q_min, planes, p1, p2, at(current, path, x));
      }
      AddFour(l_along, at(current, 0, x), at(current, 1, x), at(current, 2, x), planes, !forward,
              &sum[p * planes]);
    }
    std::swap(previous, current);
    std::swap(previous_min, current_min);
  }
}

// The least of t[0..n) (65535 when n is 0); a reduction that vectorises.
GF_VECTOR_CLONES inline int Minimum(const uint16_t* t, int n) {
  uint16_t lowest = 0xffff;
  for (int d = 0; d < n; ++d) lowest = std::min(lowest, t[d]);
  return lowest;
}

// The first index of t's least entry (n > 0), as std::min_element finds it.
inline int FirstMinimum(const uint16_t* t, int n) {
  const int lowest = Minimum(t, n);
  int d = 0;
  while (t[d] != lowest) ++d;
  return d;
}

}  // namespace gf::sweep_detail
