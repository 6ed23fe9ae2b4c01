#include "registration/rolling_shutter.h"

#include <gtest/gtest.h>

#include "tests/testing.h"

namespace gf {
namespace {

Camera Pinhole() { return testing::PinholeCamera(64, 48, 50); }

TEST(DepthAtLastRow, LeavesAStillCamerasDepthAsItIs) {
  cv::Mat depth(48, 64, CV_32FC1, cv::Scalar(1.5f));
  depth(cv::Rect(10, 10, 5, 5)).setTo(0.f);
  const cv::Mat out =
      RollingShutter(Pinhole(), 1.0 / 30).DepthAtLastRow(depth, SE3::Tangent::Zero());
  EXPECT_EQ(cv::norm(out, depth, cv::NORM_INF), 0);
}

// The camera moves towards a wall 2 m away at 0.9 m/s: row y was seen (1 - (y + 0.5) / H) of a
// 1/30 s readout before the stamp, from up to 3 cm farther; at the stamp the wall is that much
// nearer in the rows exposed first, and the last row is as measured.
TEST(DepthAtLastRow, MovesEarlyRowsToTheStampsInstant) {
  const Camera camera = Pinhole();
  const cv::Mat depth(48, 64, CV_32FC1, cv::Scalar(2.0f));
  SE3::Tangent twist = SE3::Tangent::Zero();
  twist[2] = 0.9;
  const double readout = 1.0 / 30;
  const RollingShutter shutter(camera, readout);
  const cv::Mat out = shutter.DepthAtLastRow(depth, twist);
  for (int y = 2; y < 46; y += 4) {
    const double expected = 2.0 - 0.9 * (1.0 - (y + 0.5) / 48) * readout;
    EXPECT_NEAR(out.at<float>(y, 32), expected, 2e-4) << "row " << y;
  }
  // Sideways at 0.6 m/s: the first rows' points shift by up to 2 cm, 0.5 px at 2 m; depth stays.
  twist = SE3::Tangent::Zero();
  twist[0] = 0.6;
  const cv::Mat side = shutter.DepthAtLastRow(depth, twist);
  EXPECT_EQ(cv::countNonZero(side != 2.0f), 0);
}

}  // namespace
}  // namespace gf
