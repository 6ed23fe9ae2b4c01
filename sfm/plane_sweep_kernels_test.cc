// The plane sweep's inner loops (sfm/plane_sweep_kernels.h) against their plain definitions.
#include "sfm/plane_sweep_kernels.h"

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

TEST(FirstMinimum, FindsTheFirstOfEqualMinima) {
  const std::vector<uint16_t> t = {9, 4, 7, 4, 4, 8};
  EXPECT_EQ(FirstMinimum(t.data(), 6), 1);
  EXPECT_EQ(Minimum(t.data(), 6), 4);
  EXPECT_EQ(Minimum(t.data(), 0), 0xffff);
}

}  // namespace
}  // namespace gf::sweep_detail
