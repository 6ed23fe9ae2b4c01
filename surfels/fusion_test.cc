#include "surfels/fusion.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "acquisition/errors.h"
#include "datasets/synth.h"
#include "surfels/ply.h"
#include "tests/testing.h"

namespace gf {
namespace {

// A flat wall 1.5 m in front of a camera at the origin, seen from `pose`: depth of the plane
// z_world = 1.5 (the wall faces -z).
RgbdFrame Wall(const Camera& camera, const SE3& world_from_camera, float wall_z = 1.5f) {
  RgbdFrame f;
  f.depth = cv::Mat::zeros(camera.height, camera.width, CV_32FC1);
  f.color = cv::Mat(camera.height, camera.width, CV_8UC3, cv::Scalar(40, 120, 200));
  f.hole_mask = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
  const Eigen::Vector3d c = world_from_camera.translation();
  const Eigen::Matrix3d r = world_from_camera.RotationMatrix();
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const Eigen::Vector3d ray_cam((x - camera.cx) / camera.fx, (y - camera.cy) / camera.fy, 1);
      const Eigen::Vector3d ray = r * ray_cam;
      if (ray.z() <= 0) continue;
      const double t = (wall_z - c.z()) / ray.z();  // along ray_cam: z_cam = t
      f.depth.at<float>(y, x) = static_cast<float>(t);
    }
  return f;
}

Camera SmallCamera() {
  Camera c;
  c.width = 160;
  c.height = 120;
  c.fx = c.fy = 130;
  c.cx = 79.5;
  c.cy = 59.5;
  return c;
}

SE3 At(double x, double y, double z) {
  return SE3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(x, y, z));
}

TEST(SurfelFusion, AWallSeenFromSeveralPosesConvergesToOnePlane) {
  const Camera camera = SmallCamera();
  SurfelFusion fusion(camera, {});
  int created_late = 0;
  for (int i = 0; i < 30; ++i) {
    const SE3 pose = At(0.002 * (i % 7), -0.001 * (i % 5), 0.0);
    const FusionStats s = fusion.FuseFrame(Wall(camera, pose), pose, 0);
    if (i >= 10) created_late += s.created;
  }
  const std::vector<Surfel> model = fusion.StableSurfels();
  ASSERT_GT(model.size(), 2000u);
  // Every stable surfel lies on the wall, faces the camera, and the map does not keep growing
  // once the wall is covered (new surfels only at the edges the small motion uncovers).
  for (const Surfel& s : model) {
    ASSERT_NEAR(s.position.z(), 1.5f, 0.002f);
    ASSERT_LT(s.normal.z(), -0.99f);
    EXPECT_EQ(s.source, static_cast<uint8_t>(DepthSource::kSensor));
    EXPECT_EQ(s.red, 200);  // the colour is stored as RGB
  }
  EXPECT_LT(created_late, static_cast<int>(model.size()) / 4);
  // About one surfel per 2x2 pixels (pixel_step 2): its radius covers that.
  const Surfel& centre = model[model.size() / 2];
  EXPECT_NEAR(centre.radius, std::sqrt(2.0) * 1.5 / camera.fx, 0.002);
}

// A wrong fill floating 20 cm in front of the wall: the sensor sees through it and removes it.
TEST(SurfelFusion, FreeSpaceRemovesWhatTheSensorSeesThrough) {
  const Camera camera = SmallCamera();
  SurfelFusion fusion(camera, {});
  const SE3 pose = At(0, 0, 0);
  fusion.FuseFrame(Wall(camera, pose), pose, 0);
  const RgbdFrame front = Wall(camera, pose, 1.3f);
  cv::Mat mask = cv::Mat::zeros(front.depth.size(), CV_8UC1);
  mask(cv::Rect(60, 40, 30, 30)).setTo(255);
  const cv::Mat confidence(front.depth.size(), CV_32FC1, cv::Scalar(1.f));
  fusion.FuseFill(front, front.depth, mask, confidence, DepthSource::kStereo, pose, 0);
  auto fills = [&] {
    long n = 0;
    for (const Surfel& s : fusion.map().surfels())
      n += !s.removed() && s.source == static_cast<uint8_t>(DepthSource::kStereo);
    return n;
  };
  ASSERT_GT(fills(), 100);
  fusion.FuseFrame(Wall(camera, pose), pose, 0);
  EXPECT_EQ(fills(), 0);
}

// One keyframe's fill is not enough for the model; a second one that agrees confirms it.
TEST(SurfelFusion, AFillNeedsASecondKeyframeToBecomeStable) {
  const Camera camera = SmallCamera();
  SurfelFusion fusion(camera, {});
  const SE3 pose = At(0, 0, 0);
  const RgbdFrame wall = Wall(camera, pose);
  cv::Mat mask = cv::Mat::zeros(wall.depth.size(), CV_8UC1);
  mask(cv::Rect(60, 40, 30, 30)).setTo(255);
  const cv::Mat confidence(wall.depth.size(), CV_32FC1, cv::Scalar(1.f));
  fusion.FuseFill(wall, wall.depth, mask, confidence, DepthSource::kStereo, pose, 0);
  EXPECT_EQ(fusion.Counts().stable[static_cast<int>(DepthSource::kStereo)], 0);
  EXPECT_GT(fusion.Counts().unstable[static_cast<int>(DepthSource::kStereo)], 100);
  const SE3 moved = At(0.01, 0, 0);
  const RgbdFrame again = Wall(camera, moved);
  fusion.FuseFill(again, again.depth, mask, confidence, DepthSource::kStereo, moved, 1);
  EXPECT_GT(fusion.Counts().stable[static_cast<int>(DepthSource::kStereo)], 100);
  // Unconfirmed fills go after fill_unstable_frames sensor frames; these ones stay.
  RgbdFrame nothing = wall;
  nothing.depth = cv::Mat::zeros(wall.depth.size(), CV_32FC1);
  for (int i = 0; i < 100; ++i) fusion.FuseFrame(nothing, pose, 1);
  EXPECT_GT(fusion.Counts().stable[static_cast<int>(DepthSource::kStereo)], 100);
}

// The synthetic glass table fused with its true poses: the stable surfels lie on the scene's
// surfaces (distance along their normal to the nearest surface).
TEST(SurfelFusion, TheSyntheticTableFusedWithTruePosesLiesOnItsSurfaces) {
  synth::SynthOptions options;
  options.frames = 20;
  options.seed = 3;
  const synth::Scene scene = synth::Scene::Make("glass-table", options.seed);
  const std::vector<SE3> poses = synth::MakeTrajectory(scene, options);
  const Camera camera = synth::SynthCamera();
  SurfelFusion fusion(camera, {});
  for (int i = 0; i < options.frames; ++i) {
    const RgbdFrame f = synth::ToRgbdFrame(
        synth::RenderFrame(scene, camera, poses[i], options.kinect, options.seed, i), i);
    fusion.FuseFrame(f, poses[i], 0);
  }
  const std::vector<Surfel> model = fusion.StableSurfels();
  ASSERT_GT(model.size(), 20000u);
  std::vector<double> errors;
  for (size_t i = 0; i < model.size(); i += 7) {
    const Eigen::Vector3d p = model[i].position.cast<double>(), n = model[i].normal.cast<double>();
    synth::Hit hit;
    if (scene.Intersect(p + 0.05 * n, -n, 0.0, 0.1, false, &hit))
      errors.push_back(std::abs(hit.t - 0.05));
    else
      errors.push_back(1.0);
  }
  std::sort(errors.begin(), errors.end());
  const double median = errors[errors.size() / 2], p90 = errors[errors.size() * 9 / 10];
  std::printf("%zu stable surfels: distance to the surface median %.2f mm, p90 %.2f mm\n",
              model.size(), 1000 * median, 1000 * p90);
  EXPECT_LT(median, 0.003);
  EXPECT_LT(p90, 0.01);
}

TEST(SurfelPly, RoundTrip) {
  testing::TempDir dir;
  std::vector<Surfel> surfels(3);
  for (int i = 0; i < 3; ++i) {
    surfels[i].position = Eigen::Vector3f(i, 2.f * i, -1.f);
    surfels[i].normal = Eigen::Vector3f(0, 0, 1);
    surfels[i].radius = 0.004f * (i + 1);
    surfels[i].confidence = 12.5f;
    surfels[i].red = 10, surfels[i].green = 20, surfels[i].blue = static_cast<uint8_t>(30 + i);
    surfels[i].source = static_cast<uint8_t>(i == 2 ? DepthSource::kStereo : DepthSource::kSensor);
  }
  WriteSurfelPly(dir / "map.ply", surfels);
  const std::vector<Surfel> back = ReadSurfelPly(dir / "map.ply");
  ASSERT_EQ(back.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(back[i].position, surfels[i].position);
    EXPECT_EQ(back[i].normal, surfels[i].normal);
    EXPECT_EQ(back[i].radius, surfels[i].radius);
    EXPECT_EQ(back[i].confidence, surfels[i].confidence);
    EXPECT_EQ(back[i].blue, surfels[i].blue);
    EXPECT_EQ(back[i].source, surfels[i].source);
  }
  EXPECT_THROW(ReadSurfelPly(dir / "missing.ply"), InputError);
}

}  // namespace
}  // namespace gf
