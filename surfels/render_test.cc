#include "surfels/render.h"

#include <gtest/gtest.h>

#include "tests/testing.h"

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

Camera SmallCamera() { return testing::PinholeCamera(320, 240, 300); }

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

// Discs drawn every 6 pixels along a row, 2 pixels wide, leave gaps of 4 pixels.
TEST(CloseSplatGaps, FillsNarrowGapsOnOneSurfaceAndNothingElse) {
  cv::Mat depth = cv::Mat::zeros(40, 60, CV_32FC1);
  // Row 5: pairs of pixels at x = 10, 11; 16, 17; ... 40, 41 on a plane sloping 1 mm per pixel.
  for (int x = 10; x <= 40; x += 6)
    for (int dx = 0; dx < 2; ++dx) depth.at<float>(5, x + dx) = 1.f + 0.001f * (x + dx);
  // Two discs 6 pixels apart (5 empty pixels between): a gap too wide.
  depth.at<float>(15, 10) = depth.at<float>(15, 16) = 1.f;
  // Two discs 3 pixels apart at depths 10% apart: an edge between two surfaces.
  depth.at<float>(25, 10) = 1.f;
  depth.at<float>(25, 13) = 1.1f;
  // Two discs 3 pixels apart on one surface, but the pixels between are not to be filled.
  depth.at<float>(35, 10) = depth.at<float>(35, 13) = 1.f;
  cv::Mat fillable(depth.size(), CV_8UC1, cv::Scalar(255));
  fillable.at<uint8_t>(35, 11) = fillable.at<uint8_t>(35, 12) = 0;

  const int filled = CloseSplatGaps(&depth, fillable, 4, 0.03);
  // Row 5: the 4-pixel gaps between x = 11 and 40, linear along the plane.
  for (int x = 12; x <= 41; ++x) EXPECT_NEAR(depth.at<float>(5, x), 1.f + 0.001f * x, 1e-5) << x;
  // Nothing past the drawn pixels' ends (no pixel there is enclosed on both sides).
  EXPECT_EQ(depth.at<float>(5, 9), 0.f);
  EXPECT_EQ(depth.at<float>(5, 42), 0.f);
  EXPECT_EQ(depth.at<float>(4, 20), 0.f);
  EXPECT_EQ(cv::countNonZero(depth.row(15)), 2);
  EXPECT_EQ(cv::countNonZero(depth.row(25)), 2);
  EXPECT_EQ(cv::countNonZero(depth.row(35)), 2);
  // Row 5's five gaps of 4 pixels; the rows beside it are not enclosed (one drawn row).
  EXPECT_EQ(filled, 20);
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
