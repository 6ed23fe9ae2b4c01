#include "fill/glass_frame.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

namespace gf {
namespace {

// A table seen from 45 degrees above, 0.6 m ahead, with a clear glass (a cylinder 3 cm in
// radius, 12 cm tall) standing on it; optionally an opaque box with the shadow a stereo camera
// leaves beside it. The sensor, as on real clear glass: nothing on the middle of the glass, the
// table behind it on the rest.
struct Scene {
  Camera camera;
  Eigen::Vector3d up;  // the table's normal, towards the camera
  double offset = 0;   // up . p + offset = 0 on the table
  Eigen::Vector3d base;
  double radius = 0.03, height = 0.12;
  cv::Mat truth, glass, sensor;  // CV_32F metres (the glass's own surface), CV_8U, CV_32F

  explicit Scene(bool box) {
    camera.width = 640, camera.height = 480, camera.fx = camera.fy = 525;
    camera.cx = 319.5, camera.cy = 239.5;
    const double a = M_PI / 4;
    up = Eigen::Vector3d(0, -std::cos(a), -std::sin(a));
    const Eigen::Vector3d on_table(0, 0.15, 0.6);
    offset = -up.dot(on_table);
    base = on_table + Eigen::Vector3d(0.05, 0, 0);
    base -= (up.dot(base) + offset) * up;
    truth = cv::Mat::zeros(camera.height, camera.width, CV_32F);
    glass = cv::Mat::zeros(truth.size(), CV_8U);
    sensor = cv::Mat::zeros(truth.size(), CV_32F);
    for (int y = 0; y < camera.height; ++y)
      for (int x = 0; x < camera.width; ++x) Render(x, y, box);
    // The middle of the glass reads nothing: its columns' inner 60%.
    for (int y = 0; y < camera.height; ++y) {
      int first = -1, last = -1;
      for (int x = 0; x < camera.width; ++x)
        if (glass.at<uint8_t>(y, x)) last = x, first = first < 0 ? x : first;
      const int inset = (last - first) / 5;
      for (int x = first + inset; first >= 0 && x <= last - inset; ++x) sensor.at<float>(y, x) = 0;
    }
  }

  void Render(int x, int y, bool box) {
    const Eigen::Vector3d r((x - camera.cx) / camera.fx, (y - camera.cy) / camera.fy, 1);
    const double along = up.dot(r);
    const double table = along < 0 ? -offset / along : 0;
    sensor.at<float>(y, x) = static_cast<float>(table);
    if (box && x >= 80 && x < 160 && y >= 200 && y < 280) {
      sensor.at<float>(y, x) = static_cast<float>(table - 0.06);  // an opaque box, read
    } else if (box && x >= 60 && x < 80 && y >= 200 && y < 280) {
      sensor.at<float>(y, x) = 0;  // its shadow: between the table and the box
    }
    // The glass's front: |(s r - base) across up| = radius, 0 <= height <= this.height.
    const Eigen::Vector3d w = r - r.dot(up) * up, v = -(base - base.dot(up) * up);
    const double qa = w.dot(w), qb = 2 * w.dot(v), qc = v.dot(v) - radius * radius;
    const double disc = qb * qb - 4 * qa * qc;
    if (disc < 0) return;
    const double s = (-qb - std::sqrt(disc)) / (2 * qa);
    const double h = (s * r - base).dot(up);
    if (h < 0 || h > height || (table > 0 && s > table)) return;
    truth.at<float>(y, x) = static_cast<float>(s);
    glass.at<uint8_t>(y, x) = 255;
  }

  // Share of the glass's pixels whose depth is within tolerance of its surface.
  double WithinOfGlass(const cv::Mat& depth, double tolerance) const {
    int within = 0, all = 0;
    for (int y = 0; y < truth.rows; ++y)
      for (int x = 0; x < truth.cols; ++x)
        if (glass.at<uint8_t>(y, x)) {
          ++all;
          within += std::abs(depth.at<float>(y, x) - truth.at<float>(y, x)) <= tolerance;
        }
    return all ? static_cast<double>(within) / all : 0.0;
  }
};

double IoU(const cv::Mat& a, const cv::Mat& b) {
  return static_cast<double>(cv::countNonZero(a & b)) / std::max(1, cv::countNonZero(a | b));
}

TEST(GlassFrame, FindsTheSupportPlane) {
  const Scene scene(true);
  const GlassFrameResult r = FindGlassInFrame(cv::Mat(), scene.sensor, scene.camera, {});
  ASSERT_TRUE(r.plane_found);
  EXPECT_GT(r.plane_normal.dot(scene.up), std::cos(M_PI / 180));
  EXPECT_NEAR(r.plane_offset_m, scene.offset, 0.003);
}

TEST(GlassFrame, GivenTheGlassPutsItsSurfaceIn) {
  const Scene scene(false);
  EXPECT_LT(scene.WithinOfGlass(scene.sensor, 0.01), 0.05);  // the sensor: holes and the table
  const GlassFrameResult r =
      FindGlassInFrame(cv::Mat(), scene.sensor, scene.camera, {}, scene.glass);
  ASSERT_EQ(r.regions.size(), 1u);
  EXPECT_TRUE(r.regions[0].shaped);
  EXPECT_NEAR(r.regions[0].radius_m, scene.radius, 0.01);
  EXPECT_NEAR(r.regions[0].height_m, scene.height, 0.02);
  EXPECT_GT(scene.WithinOfGlass(r.depth_filled, 0.01), 0.6);
  // Outside the glass nothing changes.
  EXPECT_EQ(cv::countNonZero((r.depth_filled != scene.sensor) & ~scene.glass), 0);
}

TEST(GlassFrame, FindsGlassFromItsHolesNotFromAShadow) {
  const Scene scene(true);
  const GlassFrameResult r = FindGlassInFrame(cv::Mat(), scene.sensor, scene.camera, {});
  EXPECT_GT(IoU(r.glass_mask, scene.glass), 0.5);
  const cv::Mat box_and_shadow = cv::Mat::zeros(scene.glass.size(), CV_8U);
  box_and_shadow(cv::Rect(60, 200, 100, 80)).setTo(255);
  EXPECT_EQ(cv::countNonZero(r.glass_mask & box_and_shadow), 0);
  EXPECT_GT(scene.WithinOfGlass(r.depth_filled, 0.01), scene.WithinOfGlass(scene.sensor, 0.01));
}

TEST(GlassFrame, NoGlassOnABareTable) {
  Scene scene(false);
  scene.sensor.setTo(0);
  const Scene bare(false);
  // The table alone, every pixel read.
  cv::Mat table = bare.sensor.clone();
  for (int y = 0; y < table.rows; ++y)
    for (int x = 0; x < table.cols; ++x) {
      const Eigen::Vector3d r((x - bare.camera.cx) / bare.camera.fx,
                              (y - bare.camera.cy) / bare.camera.fy, 1);
      table.at<float>(y, x) = static_cast<float>(-bare.offset / bare.up.dot(r));
    }
  const GlassFrameResult r = FindGlassInFrame(cv::Mat(), table, bare.camera, {});
  EXPECT_TRUE(r.plane_found);
  EXPECT_TRUE(r.regions.empty());
  EXPECT_EQ(cv::countNonZero(r.depth_filled != table), 0);
  // No depth at all: no plane, nothing found, nothing thrown.
  const GlassFrameResult none = FindGlassInFrame(cv::Mat(), scene.sensor, scene.camera, {});
  EXPECT_FALSE(none.plane_found);
  EXPECT_EQ(cv::countNonZero(none.glass_mask), 0);
}

TEST(GlassRegionsFromBoxes, CutsEachObjectOutOfItsBoxTheSameEveryTime) {
  // Two pale discs side by side on a mottled blue cloth (as glass shows the cloth, a little
  // lighter), a box round each that overlaps the other's.
  cv::Mat color(240, 320, CV_8UC3);
  cv::RNG noise(7);
  noise.fill(color, cv::RNG::UNIFORM, cv::Scalar(150, 60, 20), cv::Scalar(200, 110, 60));
  cv::GaussianBlur(color, color, cv::Size(5, 5), 2);
  cv::Mat first = cv::Mat::zeros(color.size(), CV_8U), second = first.clone();
  cv::circle(first, cv::Point(110, 120), 40, cv::Scalar(255), cv::FILLED);
  cv::circle(second, cv::Point(195, 120), 40, cv::Scalar(255), cv::FILLED);
  color.setTo(cv::Scalar(225, 215, 205), first | second);
  const std::vector<cv::Rect> boxes = {cv::Rect(60, 70, 100, 100), cv::Rect(145, 70, 100, 100),
                                       cv::Rect(400, 10, 20, 20)};
  const cv::Mat regions = GlassRegionsFromBoxes(color, boxes);
  ASSERT_EQ(regions.type(), CV_32SC1);
  EXPECT_GT(IoU(regions == 1, first & ~second), 0.85);
  EXPECT_GT(IoU(regions == 2, second), 0.85);
  EXPECT_EQ(cv::countNonZero(regions == 3), 0);  // outside the image
  cv::theRNG().next();  // whatever ran before, the same boxes give the same regions
  EXPECT_EQ(cv::countNonZero(GlassRegionsFromBoxes(color, boxes) != regions), 0);
}

TEST(GlassFrame, GivenLabelsAreOneObjectEach) {
  const Scene scene(false);
  // The glass given as two labels, its left and right parts, and label 4 on a patch of table
  // (label 3 has no pixels): three objects, not one.
  cv::Mat labels(scene.glass.size(), CV_32S, cv::Scalar(0));
  labels.setTo(1, scene.glass);
  cv::Mat right = labels.colRange(labels.cols / 2 + 50, labels.cols);
  right.setTo(2, right == 1);
  ASSERT_GT(cv::countNonZero(labels == 1), 0);
  ASSERT_GT(cv::countNonZero(labels == 2), 0);
  labels(cv::Rect(20, 400, 10, 10)).setTo(4);
  const GlassFrameResult r = FindGlassInFrame(cv::Mat(), scene.sensor, scene.camera, {}, labels);
  EXPECT_EQ(cv::countNonZero(r.glass_mask), cv::countNonZero(scene.glass) + 100);
  EXPECT_EQ(r.regions.size(), 3u);
}

TEST(GlassFrameOptions, CheckNamesTheField) {
  GlassFrameOptions o;
  std::string message;
  EXPECT_TRUE(o.Check(&message)) << message;
  o.min_radius_m = 0.5;
  EXPECT_FALSE(o.Check(&message));
  EXPECT_NE(message.find("min_radius_m"), std::string::npos) << message;
  o = GlassFrameOptions();
  o.plane_sample_step_px = 0;
  EXPECT_FALSE(o.Check(&message));
  EXPECT_NE(message.find("plane_sample_step_px"), std::string::npos) << message;
}

}  // namespace
}  // namespace gf
