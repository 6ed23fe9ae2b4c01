// Clear glass in the surfel map (FusionOptions::glass): surfaces the sensor both reads and sees
// through become transparent surfels that free space does not erase; opaque surfaces do not.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "datasets/scene.h"
#include "surfels/fusion.h"
#include "tests/testing.h"

namespace gf {
namespace {

constexpr float kPaneZ = 1.5f, kWallZ = 1.9f;
constexpr int kPatchPx = 8;

Camera SmallCamera() { return testing::PinholeCamera(160, 120, 130); }

SE3 At(double x, double y) { return SE3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(x, y, 0)); }

// Depth of the plane z_world = plane_z seen from a camera at `pose` (no rotation), pixel (x, y).
float PlaneDepth(const SE3& pose, float plane_z) {
  return static_cast<float>(plane_z - pose.translation().z());
}

// The pane spans world x, y in [-0.4, 0.4] x [-0.3, 0.3] at z = kPaneZ; grown by grow_px pixels
// all round as the camera sees it (negative: shrunk).
bool InPane(const Camera& camera, const SE3& pose, int x, int y, int grow_px = 0) {
  const double z = PlaneDepth(pose, kPaneZ);
  const double wx = (x - camera.cx) / camera.fx * z + pose.translation().x();
  const double wy = (y - camera.cy) / camera.fy * z + pose.translation().y();
  const double grow = grow_px * z / camera.fx;
  return std::abs(wx) < 0.4 + grow && std::abs(wy) < 0.3 + grow;
}

// A pane of clear glass 40 cm in front of a wall, as a depth camera reads it: each patch of
// kPatchPx pixels reads the pane (a quarter of them), the wall through it (45%) or nothing,
// drawn anew each frame; the wall around the pane reads as a wall. `opaque`: the pane is a
// painted board instead, read everywhere, its outline in the depth image grown by edge_px pixels
// (a depth edge moves by a pixel or two from frame to frame).
RgbdFrame PaneFrame(const Camera& camera, const SE3& pose, int frame, bool opaque,
                    int edge_px = 0) {
  RgbdFrame f;
  f.depth = cv::Mat::zeros(camera.height, camera.width, CV_32FC1);
  f.color = cv::Mat(camera.height, camera.width, CV_8UC3, cv::Scalar(90, 110, 120));
  f.hole_mask = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      float z = PlaneDepth(pose, kWallZ);
      if (InPane(camera, pose, x, y, opaque ? edge_px : 0)) {
        const float draw = synth::HashUniform(x / kPatchPx, y / kPatchPx, frame, 7u);
        z = opaque || draw < 0.25f ? PlaneDepth(pose, kPaneZ)
            : draw < 0.70f         ? z
                                   : 0.f;
      }
      f.depth.at<float>(y, x) = z;
    }
  return f;
}

struct PaneCounts {
  long transparent_on_pane = 0, on_pane = 0, transparent = 0, stable = 0;
};

// Fuses `frames` frames of the pane from a camera moving a few centimetres sideways; an opaque
// board's depth edge moves by up to edge_wander_px pixels each way from frame to frame.
PaneCounts FusePane(const FusionOptions& options, int frames, bool opaque,
                    int edge_wander_px = 0) {
  const Camera camera = SmallCamera();
  SurfelFusion fusion(camera, options);
  for (int i = 0; i < frames; ++i) {
    const SE3 pose = At(0.004 * (i % 9) - 0.016, 0.003 * (i % 5) - 0.006);
    const int edge_px = edge_wander_px ? (i / 3) % (2 * edge_wander_px + 1) - edge_wander_px : 0;
    fusion.FuseFrame(PaneFrame(camera, pose, i, opaque, edge_px), pose, 0);
  }
  PaneCounts c;
  for (const Surfel& s : fusion.StableSurfels()) {
    const bool pane = std::abs(s.position.z() - kPaneZ) < 0.005f;
    const bool transparent = s.source == static_cast<uint8_t>(DepthSource::kTransparent);
    c.on_pane += pane;
    c.transparent_on_pane += pane && transparent;
    c.transparent += transparent;
    ++c.stable;
  }
  return c;
}

TEST(GlassFusion, APaneTheSensorReadsAndSeesThroughStaysAsTransparentSurfels) {
  const PaneCounts glass = FusePane({}, 40, false);
  // The pane covers about 70x52 pixels at 1.5 m: some 850 surfels when it is opaque (below).
  // Read on a quarter of its 8-pixel patches, it keeps a part of them (fewer the wider
  // edge_margin_px looks around), nearly all transparent.
  EXPECT_GT(glass.on_pane, 100);
  EXPECT_GT(glass.transparent_on_pane, glass.on_pane * 9 / 10);
  // Every transparent surfel lies on the pane, none on the wall behind it.
  EXPECT_EQ(glass.transparent, glass.transparent_on_pane);

  // Without the glass rules the wall seen through the pane erases most of it.
  FusionOptions off;
  off.glass.enabled = false;
  const PaneCounts plain = FusePane(off, 40, false);
  EXPECT_EQ(plain.transparent, 0);
  EXPECT_LT(plain.on_pane, glass.on_pane / 4);
}

TEST(GlassFusion, AnOpaqueBoardIsNotGlass) {
  const PaneCounts board = FusePane({}, 40, true);
  EXPECT_GT(board.on_pane, 600);
  EXPECT_EQ(board.transparent, 0);  // its outline included
}

TEST(GlassFusion, AnOpaqueOutlineThatMovesBetweenFramesIsNotGlass) {
  // The board's depth edge grows and shrinks by up to two pixels (four from one extreme to the
  // other): the surfels near it are read on by some frames and seen past by others, as on a real
  // desk's outlines.
  const PaneCounts board = FusePane({}, 40, true, 2);
  EXPECT_GT(board.on_pane, 600);
  EXPECT_EQ(board.transparent, 0);
  // Looking only a pixel around, such outlines turn transparent (the reason for edge_margin_px).
  FusionOptions near_only;
  near_only.glass.edge_margin_px = 1;
  EXPECT_GT(FusePane(near_only, 40, true, 2).transparent, 5);
}

TEST(GlassFusion, AnObjectThatMovedAwayGoesEvenThoughItWasReadOften) {
  const Camera camera = SmallCamera();
  const FusionOptions options;
  SurfelFusion fusion(camera, options);
  const SE3 pose = At(0, 0);
  for (int i = 0; i < 20; ++i) fusion.FuseFrame(PaneFrame(camera, pose, i, true), pose, 0);
  // The board is taken away: the sensor sees the wall where it stood, every frame.
  RgbdFrame wall = PaneFrame(camera, pose, 0, true);
  wall.depth.setTo(PlaneDepth(pose, kWallZ));
  for (int i = 0; i < 3 * options.unstable_frames; ++i) fusion.FuseFrame(wall, pose, 0);
  long board = 0;
  for (const Surfel& s : fusion.map().ToVector())
    board += !s.removed() && std::abs(s.position.z() - kPaneZ) < 0.01f;
  // What is left lies on the image's border, where the free-space test has no 3x3 window.
  EXPECT_LT(board, 100);
}

TEST(GlassOptions, RefusesValuesBeyondTheirBoundsNamingTheField) {
  GlassOptions o;
  std::string message;
  EXPECT_TRUE(o.Check(&message)) << message;
  o.min_through_share = 1.5;
  EXPECT_FALSE(o.Check(&message));
  EXPECT_NE(message.find("min_through_share"), std::string::npos) << message;
  o = GlassOptions();
  o.min_readings_on = 0;
  EXPECT_FALSE(o.Check(&message));
  EXPECT_NE(message.find("min_readings_on"), std::string::npos) << message;
  o = GlassOptions();
  o.edge_margin_px = 0;
  EXPECT_FALSE(o.Check(&message));
  EXPECT_NE(message.find("edge_margin_px"), std::string::npos) << message;
  FusionOptions f;
  f.glass.stable_confidence = -1;
  EXPECT_FALSE(f.Check(&message));
  EXPECT_NE(message.find("glass.stable_confidence"), std::string::npos) << message;
}

}  // namespace
}  // namespace gf
