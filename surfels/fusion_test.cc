#include "surfels/fusion.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "acquisition/errors.h"
#include "datasets/synth.h"
#include "surfels/completeness.h"
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

Camera SmallCamera() { return testing::PinholeCamera(160, 120, 130); }

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

// Normals on the default grid (every second pixel, from whole half-size rows) and per pixel (any
// other grid, or an odd-sized image) are a ball's own, on both of the grid's offsets (the first
// frame starts at offset 1, the second at 0). A ball, not a plane: vertices taken from the wrong
// cells still lie on a plane, not on a ball.
TEST(SurfelFusion, NormalsOfABallAreRightOnEveryGrid) {
  const Eigen::Vector3f centre(0.05f, -0.03f, 1.2f);
  const float radius = 0.6f;
  Camera odd = SmallCamera();
  odd.width = 163, odd.height = 121;
  FusionOptions every_pixel;
  every_pixel.pixel_step = 1;
  for (const auto& [camera, options] :
       {std::pair(SmallCamera(), FusionOptions{}), std::pair(SmallCamera(), every_pixel),
        std::pair(odd, FusionOptions{})}) {
    RgbdFrame ball = Wall(camera, SE3()), nothing = ball;
    nothing.depth.setTo(0);
    for (int y = 0; y < camera.height; ++y)
      for (int x = 0; x < camera.width; ++x) {
        const Eigen::Vector3f ray((x - camera.cx) / camera.fx, (y - camera.cy) / camera.fy, 1);
        // |t ray - centre| = radius, the nearer t (depth, as ray.z = 1); none: 0.
        const float a = ray.squaredNorm(), b = ray.dot(centre);
        const float d = b * b - a * (centre.squaredNorm() - radius * radius);
        ball.depth.at<float>(y, x) = d > 0 ? (b - std::sqrt(d)) / a : 0.f;
      }
    for (int frames = 1; frames <= 2; ++frames) {
      SurfelFusion fusion(camera, options);
      if (frames == 2) fusion.FuseFrame(nothing, SE3(), 0);  // measures nothing
      fusion.FuseFrame(ball, SE3(), 0);
      std::vector<float> angles;
      for (size_t i = 0; i < fusion.map().size(); ++i) {
        const Surfel& s = fusion.map()[i];
        ASSERT_NEAR(s.normal.norm(), 1.f, 1e-4f);
        const float cos = s.normal.dot((s.position - centre).normalized());
        angles.push_back(std::acos(std::min(1.f, cos)) * 180.f / 3.14159f);
      }
      const std::string grid = std::to_string(camera.width) + " px, step " +
                               std::to_string(options.pixel_step) + ", frame " +
                               std::to_string(frames);
      ASSERT_GT(angles.size(), 1000u) << grid;
      std::sort(angles.begin(), angles.end());
      // On the step-2 grid at offset 1 a normal is its neighbour's, a pixel over each way (the
      // half-size depth holds the even pixels): on this ball about 0.8 degrees off.
      EXPECT_LT(angles[angles.size() / 2], 1.f) << grid;
      EXPECT_LT(angles[angles.size() * 3 / 4], 1.5f) << grid;
    }
  }
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
    for (const Surfel& s : fusion.map().ToVector())
      n += !s.removed() && s.source == static_cast<uint8_t>(DepthSource::kStereo);
    return n;
  };
  ASSERT_GT(fills(), 100);
  fusion.FuseFrame(Wall(camera, pose), pose, 0);
  EXPECT_EQ(fills(), 0);
  // The removed fills are counted as removed (compaction relies on the count).
  long live = 0;
  for (const Surfel& s : fusion.map().ToVector()) live += !s.removed();
  EXPECT_EQ(static_cast<long>(fusion.map().live()), live);
}

// A second pass over a wall, its copy of the wall 5 mm off (as a pass with a slightly different
// pose leaves it), merges into the first instead of stacking on it; a surface 20 cm behind the
// wall is a different surface and stays.
TEST(SurfelFusion, ACopyOfASurfaceMergesAndASurfaceBehindItStays) {
  const Camera camera = SmallCamera();
  SurfelFusion fusion(camera, {}), reference(camera, {});
  const SE3 pose = At(0, 0, 0);
  for (int i = 0; i < 15; ++i) fusion.FuseFrame(Wall(camera, pose), pose, 0);
  for (int i = 0; i < 18; ++i) reference.FuseFrame(Wall(camera, pose), pose, 0);
  const std::vector<Surfel> wall = fusion.StableSurfels();
  ASSERT_GT(wall.size(), 2000u);
  std::vector<Surfel> copy = wall, behind = wall;
  for (Surfel& s : copy) s.position.z() += 0.005f;
  for (Surfel& s : behind) s.position.z() += 0.2f;
  fusion.AddSurfels(copy);
  fusion.AddSurfels(behind);
  FusionStats total;
  for (int i = 0; i < 3; ++i)
    total.redundant += fusion.FuseFrame(Wall(camera, pose), pose, 0).redundant;
  EXPECT_GT(total.redundant, static_cast<int>(wall.size() * 8 / 10));
  int near_wall = 0, far_wall = 0;
  for (const Surfel& s : fusion.StableSurfels()) {
    near_wall += std::abs(s.position.z() - 1.5f) < 0.01f;
    far_wall += std::abs(s.position.z() - 1.7f) < 0.01f;
  }
  // One wall, not two: about as many surfels as the same frames fused without the copy.
  EXPECT_LT(near_wall, static_cast<int>(reference.StableSurfels().size() * 11 / 10));
  EXPECT_EQ(far_wall, static_cast<int>(behind.size()));
}

// Association compares normals only where the surfel faces the camera (|n_z| in the camera at
// least normal_test_min_facing): a surfel seen obliquely takes a measurement whatever their
// normals; one facing the camera only a measurement whose normal is within max_normal_angle_deg.
TEST(SurfelFusion, NormalsDecideAssociationOnlyWhereTheSurfelFacesTheCamera) {
  const Camera camera = SmallCamera();
  // The share of a wall frame's pixels that start a new surfel, seen from `pose`, over the
  // surfels of the same wall (all of them, to the image's edges) with their normal turned by
  // `degrees` about the world's x axis (the wall faces -z).
  auto created = [&](const SE3& pose, double degrees, const FusionOptions& options) {
    SurfelFusion first(camera, {});
    for (int i = 0; i < 15; ++i) first.FuseFrame(Wall(camera, pose), pose, 0);
    std::vector<Surfel> turned;
    const float a = static_cast<float>(degrees * M_PI / 180);
    for (Surfel s : first.map().ToVector()) {
      if (s.removed()) continue;
      s.normal = Eigen::Vector3f(0, std::sin(a), -std::cos(a));
      turned.push_back(s);
    }
    EXPECT_GT(turned.size(), 4000u);
    SurfelFusion fusion(camera, options);
    fusion.AddSurfels(turned);
    const FusionStats stats = fusion.FuseFrame(Wall(camera, pose), pose, 0);
    return static_cast<double>(stats.created) / stats.measured;
  };
  const SE3 ahead = At(0, 0, 0);
  FusionOptions every_normal;
  every_normal.normal_test_min_facing = 0;
  EXPECT_LT(created(ahead, 10, {}), 0.05);  // within the angle: merged
  EXPECT_GT(created(ahead, 35, {}), 0.95);  // facing the camera (|n_z| 0.82), beyond it: new
  EXPECT_LT(created(ahead, 60, {}), 0.05);  // oblique (|n_z| 0.5): merged whatever its normal
  EXPECT_GT(created(ahead, 60, every_normal), 0.95);
  // Facing is judged in the camera: turned 30 degrees about y, the camera sees the 35-degree
  // normals at |n_z| = cos 35 cos 30 = 0.71, obliquely (in the world frame their z is 0.82).
  const SE3 turned_camera(Eigen::AngleAxisd(30 * M_PI / 180, Eigen::Vector3d::UnitY()).matrix(),
                          Eigen::Vector3d::Zero());
  EXPECT_LT(created(turned_camera, 35, {}), 0.05);
  FusionOptions beyond_one;  // |n_z| is at most 1
  beyond_one.normal_test_min_facing = 1.5;
  EXPECT_FALSE(beyond_one.Check());
}

// Unstable surfels that left the view go within unstable_frames plus a sweep; the settled map
// elsewhere stays.
TEST(SurfelFusion, UnconfirmedSurfelsOutOfViewGo) {
  const Camera camera = SmallCamera();
  SurfelFusion fusion(camera, {});
  for (int i = 0; i < 15; ++i) fusion.FuseFrame(Wall(camera, At(0, 0, 0)), At(0, 0, 0), 0);
  const size_t settled = fusion.StableSurfels().size();
  ASSERT_GT(settled, 2000u);
  fusion.FuseFrame(Wall(camera, At(10, 0, 0)), At(10, 0, 0), 0);  // seen once: unstable
  auto near_x = [&](float x) {
    long n = 0;
    for (const Surfel& s : fusion.map().ToVector())
      n += !s.removed() && std::abs(s.position.x() - x) < 2;
    return n;
  };
  ASSERT_GT(near_x(10), 1000);
  for (int i = 0; i < FusionOptions().unstable_frames + 20; ++i)
    fusion.FuseFrame(Wall(camera, At(20, 0, 0)), At(20, 0, 0), 0);
  EXPECT_EQ(near_x(10), 0);
  EXPECT_EQ(near_x(0), static_cast<long>(settled));
}

// Unstable surfels in view that nothing confirms go after unstable_frames, at the first frame
// after it, not at the next sweep of the whole map (every 16 frames).
TEST(SurfelFusion, UnconfirmedSurfelsInViewGoWithoutWaitingForASweep) {
  const Camera camera = SmallCamera();
  const FusionOptions options;
  SurfelFusion fusion(camera, options);
  const SE3 pose = At(0, 0, 0);
  fusion.FuseFrame(Wall(camera, pose), pose, 0);  // frame 1: seen once, unstable
  const size_t seen_once = fusion.map().live();
  ASSERT_GT(seen_once, 1000u);
  ASSERT_TRUE(fusion.StableSurfels().empty());
  RgbdFrame nothing = Wall(camera, pose);  // no depth: in view, neither confirmed nor contradicted
  nothing.depth.setTo(0);
  while (fusion.frames() < 1 + options.unstable_frames) fusion.FuseFrame(nothing, pose, 0);
  EXPECT_EQ(fusion.map().live(), seen_once);  // not stale yet
  fusion.FuseFrame(nothing, pose, 0);
  ASSERT_NE(fusion.frames() % 16, 0) << "the test must end between two sweeps";
  EXPECT_EQ(fusion.map().live(), 0u);
}

// A stable surfel that free space pushes below the stable confidence is unstable from that step
// on: if nothing confirmed it for unstable_frames, it goes in that same step.
TEST(SurfelFusion, ASurfelMadeUnstableByFreeSpaceGoesWhenStale) {
  const Camera camera = SmallCamera();
  const FusionOptions options;
  SurfelFusion fusion(camera, options);
  const SE3 pose = At(0, 0, 0);
  for (int i = 0; i < 20; ++i) fusion.FuseFrame(Wall(camera, pose), pose, 0);
  const size_t stable = fusion.StableSurfels().size();
  ASSERT_GT(stable, 2000u);
  RgbdFrame nothing = Wall(camera, pose);
  nothing.depth.setTo(0);
  for (int i = 0; i <= options.unstable_frames; ++i) fusion.FuseFrame(nothing, pose, 0);
  // Stable ones stay however long unseen (a few merge as copies of their neighbours).
  ASSERT_GT(fusion.StableSurfels().size(), stable * 9 / 10);
  // The sensor now sees 30 cm past the wall, every frame: each stable surfel loses confidence
  // until it is unstable, and none stays as a stale unstable one after any step.
  for (int i = 0; i < 12; ++i) {
    fusion.FuseFrame(Wall(camera, pose, 1.8f), pose, 0);
    long stale = 0;
    for (const Surfel& s : fusion.map().ToVector())
      stale += !s.removed() && !fusion.IsStable(s) &&
               fusion.frames() - s.last_frame > options.unstable_frames;
    ASSERT_EQ(stale, 0) << "after contradiction " << i;
  }
  // The contradicted wall is (almost) gone: what is left of it lies on the image's border, where
  // the free-space test has no 3x3 window.
  long wall = 0;
  for (const Surfel& s : fusion.map().ToVector())
    wall += !s.removed() && std::abs(s.position.z() - 1.5f) < 0.01f;
  EXPECT_LT(wall, static_cast<long>(stable) / 10);
}

// A map over its budget drops the least confirmed surfels and keeps fusing.
TEST(SurfelFusion, TheMapStaysWithinItsBudget) {
  const Camera camera = SmallCamera();
  FusionOptions options;
  options.max_surfels = 1500;
  SurfelFusion fusion(camera, options);
  int over = 0;
  for (int i = 0; i < 20; ++i) {
    const SE3 pose = At(0.01 * i, 0, 0);
    over += fusion.FuseFrame(Wall(camera, pose), pose, 0).over_budget;
    ASSERT_LE(fusion.map().live(), 1500u);
  }
  EXPECT_GT(over, 0);
  EXPECT_GT(fusion.StableSurfels().size(), 500u);
}

// Fills count against the budget too: a keyframe's fill over the budget leaves the map within it.
TEST(SurfelFusion, FillsStayWithinTheBudget) {
  const Camera camera = SmallCamera();
  FusionOptions options;
  options.max_surfels = 1500;
  SurfelFusion fusion(camera, options);
  const SE3 pose = At(0, 0, 0);
  const RgbdFrame wall = Wall(camera, pose);
  fusion.FuseFrame(wall, pose, 0);
  ASSERT_LE(fusion.map().live(), 1500u);
  // A fill of a nearer wall (no surfel there to merge with): 160 x 120 new fill surfels.
  const RgbdFrame near_wall = Wall(camera, pose, 1.0f);
  const cv::Mat mask(wall.depth.size(), CV_8UC1, cv::Scalar(255));
  const cv::Mat confidence(wall.depth.size(), CV_32FC1, cv::Scalar(1.f));
  const FusionStats s =
      fusion.FuseFill(wall, near_wall.depth, mask, confidence, DepthSource::kStereo, pose, 0);
  EXPECT_GT(s.created, 1500);
  EXPECT_GT(s.over_budget, 0);
  EXPECT_LE(fusion.map().live(), 1500u);
  // A budget of one surfel holds one, whatever came.
  options.max_surfels = 1;
  SurfelFusion tiny(camera, options);
  tiny.FuseFrame(wall, pose, 0);
  tiny.FuseFill(wall, near_wall.depth, mask, confidence, DepthSource::kStereo, pose, 0);
  EXPECT_LE(tiny.map().live(), 1u);
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

// A fill is fused once, so each of its pixels starts a surfel (fill_pixel_step 1), where a sensor
// frame's grid takes one pixel in pixel_step^2 (its offset moves on with the next frame).
TEST(SurfelFusion, AFillKeepsEveryPixelWhereAFrameIsSampled) {
  const Camera camera = SmallCamera();
  const SE3 pose = At(0, 0, 0);
  const RgbdFrame wall = Wall(camera, pose);
  cv::Mat mask = cv::Mat::zeros(wall.depth.size(), CV_8UC1);
  mask(cv::Rect(60, 40, 30, 30)).setTo(255);
  const cv::Mat confidence(wall.depth.size(), CV_32FC1, cv::Scalar(1.f));
  const int pixels = cv::countNonZero(mask);
  for (int fill_step : {1, 2}) {
    FusionOptions options;
    options.fill_pixel_step = fill_step;
    SurfelFusion fusion(camera, options);
    const FusionStats s =
        fusion.FuseFill(wall, wall.depth, mask, confidence, DepthSource::kStereo, pose, 0);
    EXPECT_EQ(s.created, pixels / (fill_step * fill_step)) << "fill_pixel_step " << fill_step;
  }
  SurfelFusion fusion(camera, {});
  RgbdFrame patch = wall;
  patch.depth.setTo(0.f, mask == 0);
  // pixel_step 2; the patch's rim has no surfels (a normal needs four measured neighbours).
  const int frame_created = fusion.FuseFrame(patch, pose, 0).created;
  EXPECT_LE(frame_created, pixels / 4);
  EXPECT_GT(frame_created, pixels / 5);
  FusionOptions zero;
  zero.fill_pixel_step = 0;
  EXPECT_FALSE(zero.Check());
}

// Stereo confidences are often well under 1, so two fills' summed weights stay short of
// fill_stable_confidence; what confirms a fill is a second keyframe's fill agreeing in depth
// (within free_space_margin), not the same keyframe's fill again nor one that lies off the surface.
TEST(SurfelFusion, AFillOfAnotherKeyframeThatAgreesConfirmsItWhateverTheWeights) {
  const Camera camera = SmallCamera();
  const SE3 pose = At(0, 0, 0), moved = At(0.01, 0, 0);
  const cv::Mat confidence(camera.height, camera.width, CV_32FC1, cv::Scalar(0.3f));
  cv::Mat mask = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
  mask(cv::Rect(60, 40, 30, 30)).setTo(255);
  const int stereo = static_cast<int>(DepthSource::kStereo);
  // The second fill: keyframe and wall depth (metres); the stable fill surfels after both.
  auto stable_after = [&](int second_keyframe, float second_wall_z, bool confirm,
                          double margin = FusionOptions().free_space_margin) {
    FusionOptions options;
    options.confirm_fills_across_keyframes = confirm;
    options.free_space_margin = margin;
    SurfelFusion fusion(camera, options);
    const RgbdFrame wall = Wall(camera, pose);
    fusion.FuseFill(wall, wall.depth, mask, confidence, DepthSource::kStereo, pose, 0);
    const RgbdFrame again = Wall(camera, moved, second_wall_z);
    fusion.FuseFill(again, again.depth, mask, confidence, DepthSource::kStereo, moved,
                    second_keyframe);
    EXPECT_GT(fusion.Counts().stable[stereo] + fusion.Counts().unstable[stereo], 100);
    return fusion.Counts().stable[stereo];
  };
  EXPECT_GT(stable_after(1, 1.5f, true), 100);
  EXPECT_EQ(stable_after(1, 1.5f, false), 0);  // 0.3 * 0.5 twice is under 0.75
  EXPECT_EQ(stable_after(0, 1.5f, true), 0);   // the same keyframe's fill again
  // 4.8 cm behind: within the association's 5 cm gap, beyond 3% of the depth (and within 4%).
  EXPECT_EQ(stable_after(1, 1.548f, true), 0);
  EXPECT_GT(stable_after(1, 1.548f, true, 0.04), 100);
}

// A fill pixel that an independent view corroborated (kCorroboratedFill in the mask) is
// confirmed by its own keyframe's fill, whatever its weight; unmarked pixels of the same fill,
// or marked ones with the rule off, are not.
TEST(SurfelFusion, ACorroboratedFillIsConfirmedWithoutASecondKeyframe) {
  const Camera camera = SmallCamera();
  const SE3 pose = At(0, 0, 0);
  const cv::Mat confidence(camera.height, camera.width, CV_32FC1, cv::Scalar(0.3f));
  cv::Mat mask = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
  mask(cv::Rect(60, 40, 30, 30)).setTo(255);
  mask(cv::Rect(60, 40, 15, 30)).setTo(kCorroboratedFill);  // the left half
  const int stereo = static_cast<int>(DepthSource::kStereo);
  auto fused = [&](bool rule) {
    FusionOptions options;
    options.confirm_corroborated_fills = rule;
    SurfelFusion fusion(camera, options);
    const RgbdFrame wall = Wall(camera, pose);
    fusion.FuseFill(wall, wall.depth, mask, confidence, DepthSource::kStereo, pose, 0);
    return fusion.Counts();
  };
  const SurfelCounts on = fused(true), off = fused(false);
  // About half of the patch's surfels each way (every second pixel each way is fused).
  EXPECT_GT(on.stable[stereo], 40);
  EXPECT_GT(on.unstable[stereo], 40);
  EXPECT_NEAR(on.stable[stereo], on.unstable[stereo], 0.3 * on.unstable[stereo]);
  EXPECT_EQ(off.stable[stereo], 0);
  EXPECT_EQ(off.unstable[stereo], on.stable[stereo] + on.unstable[stereo]);
}

// The synthetic glass table fused with its true poses (sensor depth only, 40 frames): the stable
// surfels lie on the scene's surfaces, and cover what the sensor measures of it but not the
// materials it cannot measure (ScoreMap against the scene's mesh, counting the surfaces the first
// frames saw).
TEST(SurfelFusion, TheSyntheticTableFusedWithTruePosesLiesOnItsSurfaces) {
  testing::TempDir dir;
  synth::SynthOptions options;
  options.frames = 40;
  options.seed = 3;
  const synth::Scene scene = synth::Scene::Make("glass-table", options.seed);
  const std::vector<SE3> poses = synth::MakeTrajectory(scene, options);
  const Camera camera = synth::SynthCamera();
  SurfelFusion fusion(camera, {});
  std::vector<TruthView> views;
  for (int i = 0; i < options.frames; ++i) {
    const synth::SynthFrame f =
        synth::RenderFrame(scene, camera, poses[i], options.kinect, options.seed, i);
    fusion.FuseFrame(synth::ToRgbdFrame(f, i), poses[i], 0);
    if (i == 0 || i == 4) views.push_back({f.true_depth, poses[i]});  // seen 16 frames or more
  }
  const std::vector<Surfel> model = fusion.StableSurfels();
  ASSERT_GT(model.size(), 20000u);
  scene.WritePly(dir / "scene.ply");
  // Within 2.5 m, the table and what stands on it: farther, Kinect v1's depth steps (3 cm at 3 m)
  // slow the fusion down.
  CompletenessOptions near;
  near.max_depth_m = 2.5;
  const MapScore score =
      ScoreMap(model, ReadTriangleMeshPly(dir / "scene.ply"), camera, views, near);
  std::printf("%s\n", score.BriefReport().c_str());
  EXPECT_EQ(score.map_points, static_cast<long>(model.size()));
  EXPECT_LT(score.accuracy_median_m, 0.002);
  EXPECT_LT(score.accuracy_p90_m, 0.01);  // over all stable surfels, far ones too
  const auto within_2cm = [&](synth::Material m) {
    return score.per_material[static_cast<int>(m)].within[1];
  };
  std::printf("within 2 cm: diffuse %.3f, glossy %.3f, dark %.3f, textured glass %.3f\n",
              within_2cm(synth::Material::kDiffuse), within_2cm(synth::Material::kGlossy),
              within_2cm(synth::Material::kDark), within_2cm(synth::Material::kTexturedGlass));
  EXPECT_GT(within_2cm(synth::Material::kDiffuse), 0.8);
  EXPECT_LT(within_2cm(synth::Material::kGlossy), 0.3);  // no return: only its rim
  EXPECT_LT(within_2cm(synth::Material::kDark), 0.3);
}

}  // namespace
}  // namespace gf
