// SurfelFusion::RenderView: what the map knows of each pixel's surface, seen from a viewpoint.
#include <gtest/gtest.h>

#include <cmath>

#include "surfels/fusion.h"
#include "tests/testing.h"

namespace gf {
namespace {

// A flat wall at z = 1.5 m (world), seen by a camera at the origin looking along +z.
RgbdFrame Wall(const Camera& camera) {
  RgbdFrame f;
  f.depth = cv::Mat(camera.height, camera.width, CV_32FC1, cv::Scalar(1.5));  // z = 1.5 m
  f.color = cv::Mat(camera.height, camera.width, CV_8UC3, cv::Scalar(40, 120, 200));
  f.hole_mask = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
  return f;
}

SE3 Yawed(double degrees, const Eigen::Vector3d& position) {
  return SE3(Eigen::AngleAxisd(degrees * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix(),
             position);
}

// Seen from where it was measured, the wall faces the camera (cosine near 1) and its support
// grows with the frames that measured it; seen obliquely the cosine falls as the angle's; from
// behind it is negative.
TEST(SurfelFusion, RenderViewSaysHowSquarelyAndHowOftenASurfaceWasSeen) {
  const Camera camera = testing::PinholeCamera(160, 120, 130);
  SurfelFusion fusion(camera, {});
  const SE3 origin;
  for (int i = 0; i < 20; ++i) fusion.FuseFrame(Wall(camera), origin, 0);
  const MapView front = fusion.RenderView(origin, 0.03);
  ASSERT_EQ(front.depth.type(), CV_32FC1);
  const cv::Mat drawn = front.depth > 0;
  ASSERT_GT(cv::countNonZero(drawn), camera.width * camera.height / 3);  // (the rim: not stable)
  // The cosine is between the normal and each pixel's own ray: 1 on the axis, the cosine of the
  // ray's angle off the axis elsewhere (within the middle of the image: normals at the rim of the
  // measured wall lean outwards).
  const cv::Point centre(camera.width / 2, camera.height / 2);
  EXPECT_GT(front.facing.at<float>(centre), 0.99);
  cv::Mat middle = cv::Mat::zeros(drawn.size(), CV_8UC1);
  middle(cv::Rect(camera.width / 4, camera.height / 4, camera.width / 2, camera.height / 2)) = 255;
  middle &= drawn;
  for (int y = 0; y < camera.height; y += 7)
    for (int x = 0; x < camera.width; x += 7) {
      if (!middle.at<uint8_t>(y, x)) continue;
      const double off_axis = std::hypot((x - camera.cx) / camera.fx, (y - camera.cy) / camera.fy);
      EXPECT_NEAR(front.facing.at<float>(y, x), 1.0 / std::hypot(1.0, off_axis), 0.03)
          << x << ", " << y;
    }
  double min_support, max_support;
  cv::minMaxLoc(front.support, &min_support, &max_support, nullptr, nullptr, middle);
  // Each pixel's ray meets the discs of the surfels around it, each confident from the frames
  // that measured it.
  EXPECT_GT(min_support, 1.0);
  // More frames, more support at the same pixel.
  SurfelFusion twice(camera, {});
  for (int i = 0; i < 40; ++i) twice.FuseFrame(Wall(camera), origin, 0);
  const MapView more = twice.RenderView(origin, 0.03);
  ASSERT_GT(more.depth.at<float>(centre), 0.f);
  EXPECT_GT(more.support.at<float>(centre), 1.5 * front.support.at<float>(centre));
  // 60 degrees off the wall's normal, looking at its centre from the side: cosine about 0.5.
  const Eigen::Vector3d target(0, 0, 1.5);
  const SE3 side = Yawed(60, target - 1.0 * Eigen::Vector3d(std::sin(M_PI / 3), 0, std::cos(M_PI / 3)));
  const MapView oblique = fusion.RenderView(side, 0.03);
  ASSERT_GT(oblique.depth.at<float>(centre), 0.f);
  EXPECT_NEAR(oblique.facing.at<float>(centre), 0.5, 0.05);
  // From behind the wall, looking back at it: the surface faces away.
  const SE3 behind = Yawed(180, Eigen::Vector3d(0, 0, 2.5));
  const MapView back = fusion.RenderView(behind, 0.03);
  ASSERT_GT(back.depth.at<float>(centre), 0.f);
  EXPECT_LT(back.facing.at<float>(centre), -0.9);
  // The depth is RenderDepth's.
  cv::Mat source;
  const cv::Mat depth = fusion.RenderDepth(origin, &source);
  EXPECT_EQ(cv::norm(depth, front.depth, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(source, front.source, cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace gf
