#include "acquisition/depth_registration.h"

#include <gtest/gtest.h>

#include "acquisition/depth.h"
#include "tests/testing.h"

namespace gf {
namespace {

// A tilted plane n . p = d seen by a depth camera beside a colour camera with other intrinsics:
// registration must reproduce the plane's depth as the colour camera sees it, with no cracks
// inside the depth camera's view. Returns the colour pixels checked.
int ExpectThePlaneWhereTheColourCameraSeesIt(const Camera& ir, const Camera& color,
                                             const SE3& color_from_depth, double max_error_m) {
  // Plane in the colour camera's frame: z = 2.0 + 0.3 x + 0.1 y.
  const Eigen::Vector3d n_color = Eigen::Vector3d(-0.3, -0.1, 1.0);
  const double d_color = 2.0;
  auto plane_depth = [&](const Camera& cam, const SE3& world_from_cam, double u, double v) {
    // Ray p = t * r in cam; plane in colour frame: n . (R p + t0) = d.
    const Eigen::Vector2d n = cam.UndistortPixel({u, v});
    const Eigen::Vector3d rw = world_from_cam.RotationMatrix() * Eigen::Vector3d(n.x(), n.y(), 1);
    return (d_color - n_color.dot(world_from_cam.translation())) / n_color.dot(rw);  // z in cam
  };
  cv::Mat depth(ir.height, ir.width, CV_32FC1);
  for (int v = 0; v < ir.height; ++v)
    for (int u = 0; u < ir.width; ++u)
      depth.at<float>(v, u) = static_cast<float>(plane_depth(ir, color_from_depth, u, v));
  cv::Mat holes(ir.height, ir.width, CV_8UC1, cv::Scalar(0));
  cv::Mat reg_depth, reg_holes;
  RegisterDepthToColor(depth, holes, ir, color, color_from_depth, &reg_depth, &reg_holes);

  // Check the colour pixels whose plane point the IR camera sees.
  const SE3 depth_from_color = color_from_depth.Inverse();
  int covered = 0, checked = 0;
  double max_error = 0;
  for (int v = 0; v < color.height; ++v) {
    for (int u = 0; u < color.width; ++u) {
      const double z_color = plane_depth(color, SE3(), u, v);
      const Eigen::Vector2d n = color.UndistortPixel({u, v});
      const Eigen::Vector2d in_ir = ir.ProjectDistorted(
          depth_from_color * Eigen::Vector3d(n.x() * z_color, n.y() * z_color, z_color));
      if (in_ir.x() < 1 || in_ir.y() < 1 || in_ir.x() > ir.width - 2 ||
          in_ir.y() > ir.height - 2)
        continue;
      ++checked;
      const float z = reg_depth.at<float>(v, u);
      if (z <= 0) continue;
      ++covered;
      max_error = std::max(max_error, std::abs(z - z_color));
    }
  }
  EXPECT_GT(covered, 0.995 * checked);
  EXPECT_LT(max_error, max_error_m);
  return checked;
}

// A Kinect-like pair: pinhole cameras 2.5 cm apart, the IR camera's view narrower (fx 580).
TEST(RegisterDepthToColor, TiltedPlaneLandsWhereTheColourCameraSeesIt) {
  Camera ir;
  ir.fx = ir.fy = 580.0;
  ir.cx = 314.5;
  ir.cy = 235.5;
  Camera color;
  color.fx = color.fy = 525.0;
  color.cx = 319.5;
  color.cy = 239.5;
  const SE3 color_from_depth(Eigen::Quaterniond(Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitY())),
                             Eigen::Vector3d(-0.025, 0.001, 0.002));
  // The nearest-surface splat is within the depth change across its footprint (slope 0.3 at
  // 2.6 m: about 1.4 mm per IR pixel, so under 3 mm).
  EXPECT_GT(ExpectThePlaneWhereTheColourCameraSeesIt(ir, color, color_from_depth, 0.003), 200000);
}

// The Azure Kinect's pair: both lenses far from pinholes (the depth camera's corners 20 pixels
// off), colour at twice the depth camera's size, 3.2 cm apart.
TEST(RegisterDepthToColor, DistortedLensesPutThePlaneWhereTheColourCameraSeesIt) {
  const SE3 color_from_depth(Eigen::Quaterniond(Eigen::AngleAxisd(0.006, Eigen::Vector3d::UnitX())),
                             Eigen::Vector3d(-0.032, -0.0022, 0.0039));
  // A depth pixel near the corners spans 1.3 times the angle of one at the centre (fx 505
  // against 580 above, too): its footprint's depth change on the plane is up to 4.5 mm.
  EXPECT_GT(ExpectThePlaneWhereTheColourCameraSeesIt(testing::AzureKinectNfovDepthCamera(),
                                                     testing::AzureKinect720pColorCamera(),
                                                     color_from_depth, 0.0045),
            500000);
}

TEST(RegisterDepthToColor, HolesKeepTheirClassAndNearSurfacesWin) {
  Camera cam;  // same camera, pure translation: a fronto-parallel scene shifts by f*b/z pixels
  const SE3 color_from_depth(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.05, 0, 0));
  cv::Mat depth(480, 640, CV_32FC1, cv::Scalar(2.0f));
  cv::Mat holes(480, 640, CV_8UC1, cv::Scalar(0));
  depth(cv::Rect(300, 200, 40, 40)).setTo(1.0f);  // a near box
  depth(cv::Rect(100, 100, 20, 20)).setTo(0.0f);  // a glass patch: no return
  holes(cv::Rect(100, 100, 20, 20)).setTo(static_cast<uint8_t>(HoleCode::kNoReturn));
  cv::Mat reg_depth, reg_holes;
  RegisterDepthToColor(depth, holes, cam, cam, color_from_depth, &reg_depth, &reg_holes);
  // Box moves by 525 * 0.05 / 1.0 = 26.25 px, background by 13.1 px.
  EXPECT_FLOAT_EQ(reg_depth.at<float>(220, 300 + 26 + 20), 1.0f);
  EXPECT_FLOAT_EQ(reg_depth.at<float>(220, 300 + 26 + 50), 2.0f);
  // The glass hole moved with the background and is still a no-return hole.
  EXPECT_EQ(reg_holes.at<uint8_t>(110, 110 + 13), static_cast<uint8_t>(HoleCode::kNoReturn));
  EXPECT_EQ(reg_depth.at<float>(110, 110 + 13), 0.0f);
  // Columns the depth camera never saw (left edge after the shift) are out of view.
  EXPECT_EQ(reg_holes.at<uint8_t>(240, 2), static_cast<uint8_t>(HoleCode::kOutOfRange));
}

TEST(ClassifyShadows, MarksTheStripLeftOfANearObjectOnly) {
  // Background at 3 m, a box at 1.5 m over columns [300, 400). With the projector 7.5 cm to the
  // right, the shadow is 525 * 0.075 * (1/1.5 - 1/3) = 13.1 px wide, left of the box.
  const double fx = 525.0;
  cv::Mat depth(10, 640, CV_32FC1, cv::Scalar(3.0f));
  cv::Mat holes(10, 640, CV_8UC1, cv::Scalar(0));
  depth.colRange(300, 400).setTo(1.5f);
  auto hole = [&](int from, int to) {
    depth.colRange(from, to).setTo(0.f);
    holes.colRange(from, to).setTo(static_cast<uint8_t>(HoleCode::kNoReturn));
  };
  hole(287, 300);  // the projector shadow
  hole(400, 410);  // a hole right of the box: the wrong side for a shadow
  hole(100, 130);  // a glass pane on the background: no depth step
  const size_t marked = ClassifyShadows(depth, fx, ShadowOptions{}, &holes);
  EXPECT_EQ(marked, 13u * 10);
  EXPECT_EQ(holes.at<uint8_t>(5, 290), static_cast<uint8_t>(HoleCode::kShadow));
  EXPECT_EQ(holes.at<uint8_t>(5, 405), static_cast<uint8_t>(HoleCode::kNoReturn));
  EXPECT_EQ(holes.at<uint8_t>(5, 110), static_cast<uint8_t>(HoleCode::kNoReturn));

  // A hole far wider than the parallax allows is not a shadow (glass next to the box).
  cv::Mat holes2(10, 640, CV_8UC1, cv::Scalar(0));
  cv::Mat depth2 = cv::Mat(10, 640, CV_32FC1, cv::Scalar(3.0f));
  depth2.colRange(300, 400).setTo(1.5f);
  depth2.colRange(250, 300).setTo(0.f);
  holes2.colRange(250, 300).setTo(static_cast<uint8_t>(HoleCode::kNoReturn));
  EXPECT_EQ(ClassifyShadows(depth2, fx, ShadowOptions{}, &holes2), 0u);
}

TEST(ClassifyShadows, ContinuesAShadowDownAClearGlassObject) {
  // A bottle at 1.5 m over columns [300, 400) in front of a 3 m background: a measured label in
  // rows [0, 10), clear glass (no return) in rows [10, 30). Its shadow (13 px, left of it) is a
  // run of its own beside the label, but merges with the glass below it into one no-return run
  // between two far sides, which the row test cannot split.
  const double fx = 525.0;
  cv::Mat depth(30, 640, CV_32FC1, cv::Scalar(3.0f));
  cv::Mat holes(30, 640, CV_8UC1, cv::Scalar(0));
  depth(cv::Rect(300, 0, 100, 10)).setTo(1.5f);
  depth(cv::Rect(287, 0, 13, 30)).setTo(0.f);  // the shadow
  holes(cv::Rect(287, 0, 13, 30)).setTo(static_cast<uint8_t>(HoleCode::kNoReturn));
  depth(cv::Rect(300, 10, 100, 20)).setTo(0.f);  // the glass
  holes(cv::Rect(300, 10, 100, 20)).setTo(static_cast<uint8_t>(HoleCode::kNoReturn));
  const cv::Mat original = holes.clone();

  ShadowOptions rows_only;
  rows_only.continue_vertically = false;
  cv::Mat by_rows = original.clone();
  EXPECT_EQ(ClassifyShadows(depth, fx, rows_only, &by_rows), 13u * 10);
  EXPECT_EQ(by_rows.at<uint8_t>(20, 290), static_cast<uint8_t>(HoleCode::kNoReturn));

  // Continued down the glass rows, as wide as the shadow above; the glass stays no-return.
  EXPECT_EQ(ClassifyShadows(depth, fx, ShadowOptions{}, &holes), 13u * 30);
  for (int y : {0, 9, 10, 29}) {
    EXPECT_EQ(holes.at<uint8_t>(y, 287), static_cast<uint8_t>(HoleCode::kShadow)) << y;
    EXPECT_EQ(holes.at<uint8_t>(y, 299), static_cast<uint8_t>(HoleCode::kShadow)) << y;
  }
  EXPECT_EQ(holes.at<uint8_t>(20, 300), static_cast<uint8_t>(HoleCode::kNoReturn));
  EXPECT_EQ(holes.at<uint8_t>(20, 399), static_cast<uint8_t>(HoleCode::kNoReturn));

  // Without a shadow run to continue from (glass the whole height), nothing is marked; nor where
  // the far side beside the run is at another depth than beside the shadow above it.
  cv::Mat all_glass_depth = depth.clone(), all_glass = original.clone();
  all_glass_depth(cv::Rect(300, 0, 100, 10)).setTo(0.f);
  all_glass(cv::Rect(300, 0, 100, 10)).setTo(static_cast<uint8_t>(HoleCode::kNoReturn));
  EXPECT_EQ(ClassifyShadows(all_glass_depth, fx, ShadowOptions{}, &all_glass), 0u);
  cv::Mat other_far = depth.clone(), other_far_holes = original.clone();
  other_far(cv::Rect(0, 10, 287, 20)).setTo(2.0f);
  EXPECT_EQ(ClassifyShadows(other_far, fx, ShadowOptions{}, &other_far_holes), 13u * 10);
}

}  // namespace
}  // namespace gf
