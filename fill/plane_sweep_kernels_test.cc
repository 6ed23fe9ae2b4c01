// The plane sweep's inner loops (fill/plane_sweep_kernels.h) against their plain definitions.
#include "fill/plane_sweep_kernels.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

namespace gf::sweep_detail {
namespace {

// Rows whose depth crosses zero, at either end, or not at all; and a homography that is not finite.
TEST(SamplePositions, MatchesTheHomographyAndMarksPixelsBehindTheCamera) {
  std::mt19937 random(7);
  std::uniform_real_distribution<float> entry(-2.f, 2.f);
  int behind = 0, ahead = 0;
  for (int trial = 0; trial < 200; ++trial) {
    float h[9];
    for (float& v : h) v = entry(random);
    h[6] *= 0.02f;  // the depth changes sign somewhere along some rows
    const int y = trial % 50, n = 61;
    std::vector<float> u(n), v(n);
    SamplePositions(h, true, y, n, u.data(), v.data());
    for (int x = 0; x < n; ++x) {
      const float qz = h[7] * y + h[8] + h[6] * x;
      if (qz > 1e-9f) {
        ++ahead;
        EXPECT_FLOAT_EQ(u[x], (h[1] * y + h[2] + h[0] * x) / qz) << trial << " " << x;
        EXPECT_FLOAT_EQ(v[x], (h[4] * y + h[5] + h[3] * x) / qz) << trial << " " << x;
      } else {
        ++behind;
        EXPECT_EQ(u[x], -1.f) << trial << " " << x;
        EXPECT_EQ(v[x], -1.f) << trial << " " << x;
      }
    }
  }
  EXPECT_GT(behind, 1000);
  EXPECT_GT(ahead, 1000);
  const float h[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::vector<float> u(5), v(5);
  SamplePositions(h, false, 3, 5, u.data(), v.data());
  EXPECT_EQ(u, std::vector<float>(5, -1.f));
  EXPECT_EQ(v, std::vector<float>(5, -1.f));
}

// Semi-global aggregation as Hirschmueller defines it, one path at a time, for reference.
std::vector<uint16_t> AggregateByPath(const std::vector<uint8_t>& cost, int rows, int cols,
                                      int planes, int p1, int p2) {
  std::vector<uint16_t> sum(cost.size(), 0);
  const int paths[8][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {-1, 1}, {1, -1}, {-1, -1}};
  for (const auto& [dx, dy] : paths) {
    std::vector<int> l(cost.size());
    for (int i = 0; i < rows; ++i) {
      const int y = dy >= 0 ? i : rows - 1 - i;
      for (int j = 0; j < cols; ++j) {
        const int x = dx >= 0 ? j : cols - 1 - j;
        const size_t p = (static_cast<size_t>(y) * cols + x) * planes;
        const int px = x - dx, py = y - dy;
        const bool start = px < 0 || px >= cols || py < 0 || py >= rows;
        const size_t q = start ? 0 : (static_cast<size_t>(py) * cols + px) * planes;
        const int q_min = start ? 0 : *std::min_element(&l[q], &l[q] + planes);
        for (int d = 0; d < planes; ++d) {
          int v = 0;
          if (!start) {
            v = std::min(l[q + d], q_min + p2);
            if (d > 0) v = std::min(v, l[q + d - 1] + p1);
            if (d + 1 < planes) v = std::min(v, l[q + d + 1] + p1);
            v -= q_min;
          }
          l[p + d] = cost[p + d] + v;
          sum[p + d] = static_cast<uint16_t>(sum[p + d] + l[p + d]);
        }
      }
    }
  }
  return sum;
}

TEST(AggregatePass, TwoPassesGiveTheEightPaths) {
  std::mt19937 random(3);
  std::uniform_int_distribution<int> value(0, 200);
  const int rows = 13, cols = 17, planes = 21;
  std::vector<uint8_t> cost(static_cast<size_t>(rows) * cols * planes);
  for (uint8_t& c : cost) c = static_cast<uint8_t>(value(random));
  std::vector<uint16_t> sum(cost.size(), 0xbeef);  // the forward pass overwrites whatever is there
  for (bool forward : {true, false})
    AggregatePass(cost.data(), rows, cols, planes, forward, 4, 40, sum.data());
  EXPECT_EQ(sum, AggregateByPath(cost, rows, cols, planes, 4, 40));
}

// Every output row's sums of one WindowSums run, channel-major, with the spans they were valid in.
struct RunSums {
  std::vector<std::vector<float>> rows;
  std::vector<Spans> spans;
};
RunSums RunWindowSums(const ViewData& view, const Eigen::Matrix3d& h, const cv::Mat& i_roi,
                      const cv::Mat& c_roi, const cv::Mat& h_roi, const cv::Mat& active,
                      int window) {
  WindowSums sums(i_roi.rows, i_roi.cols, window, true);
  RunSums out;
  out.rows.resize(i_roi.rows);
  out.spans.resize(i_roi.rows);
  sums.Run(view, h, i_roi, c_roi, h_roi, ActiveColumns(active, window / 2),
           [&](int y, const float* m, const Spans& spans) {
             out.rows[y].assign(m, m + 8 * i_roi.cols);
             out.spans[y] = spans;
           });
  return out;
}

// Window sums computed on part of the image equal those of the whole image where they are
// computed (bit for bit: the same operations in the same order), and both equal the window sums'
// definition (a box sum of the sampled channels, up to float rounding).
TEST(WindowSums, PartsOfTheImageGiveTheWholeImagesSums) {
  std::mt19937 random(11);
  std::uniform_real_distribution<float> grey(0.f, 255.f), unit(0.f, 1.f);
  const int rows = 37, cols = 53, window = 7, half = 3;
  ViewData view;
  view.gray = cv::Mat(rows + 6, cols + 6, CV_32F);
  for (int y = 0; y < view.gray.rows; ++y)
    for (int x = 0; x < view.gray.cols; ++x) view.gray.at<float>(y, x) = grey(random);
  cv::Mat i_roi(rows, cols, CV_32F), c_roi(rows, cols, CV_32F), h_roi(rows, cols, CV_32F);
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x) {
      i_roi.at<float>(y, x) = grey(random);
      c_roi.at<float>(y, x) = unit(random) < 0.9f ? 1.f : 0.f;
      h_roi.at<float>(y, x) = c_roi.at<float>(y, x) * (unit(random) < 0.5f ? 1.f : 0.f);
    }
  Eigen::Matrix3d h;  // a slight warp, some samples outside the view's image
  h << 1.02, 0.01, 2.3, -0.015, 0.99, 3.7, 1e-4, -2e-4, 1.0;
  const RunSums whole = RunWindowSums(view, h, i_roi, c_roi, h_roi,
                                      cv::Mat(rows, cols, CV_8UC1, cv::Scalar(1)), window);
  cv::Mat active(rows, cols, CV_8UC1, cv::Scalar(0));
  active(cv::Rect(2, 3, 5, 4)).setTo(1);
  active(cv::Rect(30, 12, 20, 3)).setTo(1);
  active(cv::Rect(10, 30, 2, 7)).setTo(1);
  const RunSums part = RunWindowSums(view, h, i_roi, c_roi, h_roi, active, window);
  // The sampled channels, as SampleRow and WeightByHoles give them (0 outside the ROI).
  std::vector<cv::Mat> channel(8);
  for (cv::Mat& c : channel) c = cv::Mat(rows + 2 * half, cols + 2 * half, CV_32F, cv::Scalar(0));
  std::vector<float> u(cols), v(cols), row(4 * cols);
  float hf[9];
  for (int i = 0; i < 9; ++i) hf[i] = static_cast<float>(h(i / 3, i % 3));
  for (int y = 0; y < rows; ++y) {
    SamplePositions(hf, true, y, cols, u.data(), v.data());
    SampleRow(view, u.data(), v.data(), cols, i_roi.ptr<float>(y), c_roi.ptr<float>(y), &row[0],
              &row[cols], &row[2 * cols], &row[3 * cols]);
    for (int c = 0; c < 4; ++c)
      for (int x = 0; x < cols; ++x) {
        channel[c].at<float>(y + half, x + half) = row[c * cols + x];
        channel[c + 4].at<float>(y + half, x + half) = row[c * cols + x] * h_roi.at<float>(y, x);
      }
  }
  int compared = 0;
  for (int y = 0; y < rows; ++y) {
    ASSERT_EQ(whole.spans[y].size(), 1u);
    for (int c = 0; c < 8; ++c)
      for (int x = 0; x < cols; ++x) {
        const double box = cv::sum(channel[c](cv::Rect(x, y, window, window)))[0];
        EXPECT_NEAR(whole.rows[y][c * cols + x], box, 1e-3 * (1 + std::abs(box)))
            << c << " " << x << " " << y;
      }
    for (const Span& s : part.spans[y])
      for (int x = s.begin; x < s.end; ++x, ++compared)
        for (int c = 0; c < 8; ++c)
          ASSERT_EQ(part.rows[y][c * cols + x], whole.rows[y][c * cols + x])
              << c << " " << x << " " << y;
  }
  // Every active pixel was computed, and far from all of the image.
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x)
      if (active.at<uint8_t>(y, x))
        EXPECT_TRUE(std::any_of(part.spans[y].begin(), part.spans[y].end(),
                                [&](const Span& s) { return s.begin <= x && x < s.end; }))
            << x << " " << y;
  EXPECT_GT(compared, 100);
  EXPECT_LT(compared, rows * cols / 2);
}

TEST(FirstMinimum, FindsTheFirstOfEqualMinima) {
  const std::vector<uint16_t> t = {9, 4, 7, 4, 4, 8};
  EXPECT_EQ(FirstMinimum(t.data(), 6), 1);
  EXPECT_EQ(Minimum(t.data(), 6), 4);
  EXPECT_EQ(Minimum(t.data(), 0), 0xffff);
}

}  // namespace
}  // namespace gf::sweep_detail
