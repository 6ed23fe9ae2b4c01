#include "surfels/render.h"

#include <gtest/gtest.h>

namespace gf {
namespace {

// A 1 m square of surfels in the plane z = 2 (world), facing -z, 5 mm apart.
std::vector<Surfel> Square() {
  std::vector<Surfel> out;
  for (int i = 0; i < 200; ++i)
    for (int j = 0; j < 200; ++j) {
      Surfel s;
      s.position = Eigen::Vector3f(-0.5f + 0.005f * i, -0.5f + 0.005f * j, 2.f);
      s.normal = Eigen::Vector3f(0, 0, -1);
      s.radius = 0.004f;
      s.red = 200, s.green = 100, s.blue = 50;
      out.push_back(s);
    }
  return out;
}

Camera SmallCamera() {
  Camera camera;
  camera.width = 320;
  camera.height = 240;
  camera.fx = camera.fy = 300;
  camera.cx = 159.5;
  camera.cy = 119.5;
  return camera;
}

TEST(RenderSurfels, DrawsTheSquareAtItsDepthWithItsColour) {
  const Camera camera = SmallCamera();
  const SurfelImage image = RenderSurfels(Square(), camera, SE3(), {});
  // The square spans +-0.5 m at 2 m: +-75 px around the centre, with no gaps between discs.
  EXPECT_FLOAT_EQ(image.depth.at<float>(120, 160), 2.f);
  EXPECT_EQ(cv::countNonZero(image.depth(cv::Rect(90, 50, 140, 140)) > 0), 140 * 140);
  EXPECT_EQ(image.depth.at<float>(10, 10), 0.f);
  EXPECT_EQ(image.color.at<cv::Vec3b>(10, 10), cv::Vec3b(255, 255, 255));
  EXPECT_EQ(image.color.at<cv::Vec3b>(120, 160), cv::Vec3b(50, 100, 200));  // facing: unshaded
  // Seen from behind the plane, nothing is in front of the camera.
  const SE3 behind(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 3));
  EXPECT_EQ(cv::countNonZero(RenderSurfels(Square(), camera, behind, {}).depth), 0);
}

TEST(ViewOfMap, FramesTheWholeMap) {
  const Camera camera = SmallCamera();
  // From above and in front, with world -y up.
  const SE3 view = ViewOfMap(Square(), camera, Eigen::Vector3d(0, 1, 1), Eigen::Vector3d(0, -1, 0));
  const SurfelImage image = RenderSurfels(Square(), camera, view, {});
  const cv::Mat drawn = image.depth > 0;
  EXPECT_GT(cv::countNonZero(drawn), 5000);
  // The centroid is at the image centre and nothing touches the border.
  EXPECT_GT(image.depth.at<float>(120, 160), 0.f);
  EXPECT_EQ(cv::countNonZero(drawn.row(0)) + cv::countNonZero(drawn.row(239)), 0);
}

}  // namespace
}  // namespace gf
