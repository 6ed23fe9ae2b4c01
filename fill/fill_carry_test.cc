#include "fill/fill_carry.h"

#include <gtest/gtest.h>

#include <cmath>

#include "acquisition/depth.h"
#include "tests/testing.h"

namespace gf {
namespace {

// A wall at world z = kWall (metres) seen by cameras that look along world z; a square hole in the
// middle of every keyframe's depth (a glass pane in the wall). TUM-like lens distortion, so that
// carrying exercises the distorted projection both ways.
constexpr double kWall = 2.0;
const cv::Rect kHole(260, 180, 120, 120);

SE3 CameraAt(double x, double y, double z) {
  return SE3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(x, y, z));
}

// The keyframe's sensor view of the wall (identity rotation: depth kWall - z everywhere), empty in
// the hole.
RgbdFrame WallFrame(const SE3& world_from_camera) {
  RgbdFrame f;
  const float depth = static_cast<float>(kWall - world_from_camera.translation().z());
  f.depth = cv::Mat(480, 640, CV_32FC1, cv::Scalar(depth));
  f.hole_mask = cv::Mat::zeros(480, 640, CV_8UC1);
  f.depth(kHole).setTo(0.f);
  f.hole_mask(kHole).setTo(static_cast<uint8_t>(HoleCode::kNoReturn));
  return f;
}

// A stereo result that filled the hole of `frame` at `scale` times the true depth.
StereoFillResult OwnFill(const RgbdFrame& frame, double scale) {
  StereoFillResult r;
  r.success = true;
  r.filled_depth = frame.depth.clone();
  const float truth = frame.depth.at<float>(0, 0);
  r.filled_depth(kHole).setTo(static_cast<float>(truth * scale));
  r.fill_mask = cv::Mat::zeros(frame.depth.size(), CV_8UC1);
  r.fill_mask(kHole).setTo(255);
  r.source =
      cv::Mat(frame.depth.size(), CV_8UC1, cv::Scalar(static_cast<uint8_t>(DepthSource::kSensor)));
  r.source(kHole).setTo(static_cast<uint8_t>(DepthSource::kStereo));
  r.confidence = cv::Mat::ones(frame.depth.size(), CV_32FC1);
  r.filled_pixels = kHole.area();
  return r;
}

KeyframeFillPoints EarlierFill(const SE3& world_from_camera, double scale = 1.0) {
  return FillPointsInWorld(OwnFill(WallFrame(world_from_camera), scale), world_from_camera,
                           testing::TumFr1Camera());
}

std::vector<const KeyframeFillPoints*> Pointers(const std::vector<KeyframeFillPoints>& v) {
  std::vector<const KeyframeFillPoints*> p;
  for (const KeyframeFillPoints& e : v) p.push_back(&e);
  return p;
}

// Hole pixels of r within `tolerance` (relative) of the wall's true depth in the keyframe.
int WithinOfTruth(const CarriedFillResult& r, double truth, double tolerance) {
  int n = 0;
  for (int y = kHole.y; y < kHole.br().y; ++y)
    for (int x = kHole.x; x < kHole.br().x; ++x) {
      const float d = r.filled_depth.at<float>(y, x);
      n += d > 0 && std::abs(d - truth) <= tolerance * truth;
    }
  return n;
}

TEST(FillCarry, EarlierKeyframesThatAgreeFillAnEmptyHole) {
  const SE3 key1_pose = CameraAt(0.02, 0.01, 0.05);
  const RgbdFrame key1 = WallFrame(key1_pose);
  // The earlier keyframes' panes overlap key1's only in part: each sees the wall from elsewhere.
  const std::vector<KeyframeFillPoints> earlier = {EarlierFill(CameraAt(0, 0, 0)),
                                                   EarlierFill(CameraAt(0.05, 0, 0.02)),
                                                   EarlierFill(CameraAt(-0.03, 0.04, 0.08))};
  const CarriedFillResult r = CarryFills(key1, key1_pose, nullptr, Pointers(earlier),
                                         testing::TumFr1Camera(), FillCarryOptions{});
  const double truth = kWall - 0.05;
  // Most of the hole is filled (the rest lies outside two of the three panes), all of it right.
  EXPECT_GT(r.carried_pixels, kHole.area() * 0.6) << r.BriefReport();
  EXPECT_EQ(r.carried_pixels, r.filled_pixels);
  EXPECT_EQ(WithinOfTruth(r, truth, 0.002), r.carried_pixels);
  EXPECT_EQ(r.corrected_pixels, 0);
  for (int y = kHole.y; y < kHole.br().y; ++y)
    for (int x = kHole.x; x < kHole.br().x; ++x)
      if (r.fill_mask.at<uint8_t>(y, x)) {
        EXPECT_EQ(r.source.at<uint8_t>(y, x), static_cast<uint8_t>(DepthSource::kCarried));
        EXPECT_GT(r.confidence.at<float>(y, x), 0.5f);
      }
  // Measured pixels are never changed, though the earlier panes project onto some of them.
  cv::Mat outside = cv::Mat::ones(key1.depth.size(), CV_8UC1);
  outside(kHole).setTo(0);
  cv::Mat diff;
  cv::absdiff(r.filled_depth, key1.depth, diff);
  double most = 0;
  cv::minMaxLoc(diff, nullptr, &most, nullptr, nullptr, outside);
  EXPECT_EQ(most, 0.0);
  EXPECT_EQ(cv::countNonZero(r.fill_mask & outside), 0);
}

TEST(FillCarry, OneKeyframeAloneCarriesNothing) {
  const SE3 key1_pose = CameraAt(0.02, 0, 0.03);
  const std::vector<KeyframeFillPoints> earlier = {EarlierFill(CameraAt(0, 0, 0))};
  const CarriedFillResult r =
      CarryFills(WallFrame(key1_pose), key1_pose, nullptr, Pointers(earlier),
                 testing::TumFr1Camera(), FillCarryOptions{});
  EXPECT_EQ(r.filled_pixels, 0);
  FillCarryOptions one;
  one.min_agreeing = 1;
  EXPECT_GT(CarryFills(WallFrame(key1_pose), key1_pose, nullptr, Pointers(earlier),
                       testing::TumFr1Camera(), one)
                .carried_pixels,
            kHole.area() / 2);
}

TEST(FillCarry, KeyframesThatDisagreeCarryNothing) {
  const SE3 key1_pose = CameraAt(0.02, 0, 0.03);
  // Two earlier fills 10% apart in depth: neither has a second keyframe within 2%.
  const std::vector<KeyframeFillPoints> earlier = {EarlierFill(CameraAt(0, 0, 0), 1.0),
                                                   EarlierFill(CameraAt(0.03, 0, 0), 1.1)};
  const CarriedFillResult r =
      CarryFills(WallFrame(key1_pose), key1_pose, nullptr, Pointers(earlier),
                 testing::TumFr1Camera(), FillCarryOptions{});
  EXPECT_EQ(r.filled_pixels, 0) << r.BriefReport();
}

TEST(FillCarry, ConsensusReplacesADisagreeingOwnFill) {
  const SE3 key1_pose = CameraAt(0.01, 0, 0.02);
  const RgbdFrame key1 = WallFrame(key1_pose);
  const StereoFillResult own = OwnFill(key1, 1.06);  // 6% too far
  const std::vector<KeyframeFillPoints> earlier = {EarlierFill(CameraAt(0, 0, 0)),
                                                   EarlierFill(CameraAt(0.02, 0, 0)),
                                                   EarlierFill(CameraAt(0.01, 0.01, 0.03))};
  const double truth = kWall - 0.02;
  const CarriedFillResult r = CarryFills(key1, key1_pose, &own, Pointers(earlier),
                                         testing::TumFr1Camera(), FillCarryOptions{});
  EXPECT_GT(r.corrected_pixels, kHole.area() * 0.8) << r.BriefReport();
  EXPECT_EQ(r.carried_pixels, 0);  // the own fill covered the whole hole
  EXPECT_EQ(r.filled_pixels, kHole.area());
  EXPECT_EQ(WithinOfTruth(r, truth, 0.002), r.corrected_pixels);

  FillCarryOptions keep;
  keep.correct_own_fills = false;
  const CarriedFillResult kept =
      CarryFills(key1, key1_pose, &own, Pointers(earlier), testing::TumFr1Camera(), keep);
  EXPECT_EQ(kept.corrected_pixels, 0);
  EXPECT_EQ(WithinOfTruth(kept, truth * 1.06, 0.001), kHole.area());

  // An own fill that agrees with the consensus stays as it is.
  const StereoFillResult right = OwnFill(key1, 1.0);
  EXPECT_EQ(CarryFills(key1, key1_pose, &right, Pointers(earlier), testing::TumFr1Camera(), {})
                .corrected_pixels,
            0);
}

TEST(FillCarry, OnlyOwnStereoFillsAreCarriedOn) {
  const SE3 pose = CameraAt(0, 0, 0);
  StereoFillResult r = OwnFill(WallFrame(pose), 1.0);
  EXPECT_EQ(FillPointsInWorld(r, pose, testing::TumFr1Camera()).world_points.size(),
            static_cast<size_t>(kHole.area()));
  r.source(kHole).setTo(static_cast<uint8_t>(DepthSource::kCarried));
  EXPECT_TRUE(FillPointsInWorld(r, pose, testing::TumFr1Camera()).world_points.empty());
  r.success = false;
  EXPECT_TRUE(FillPointsInWorld(r, pose, testing::TumFr1Camera()).world_points.empty());
}

TEST(FillCarry, OptionsCheck) {
  FillCarryOptions o;
  EXPECT_TRUE(o.Check());
  o.min_agreeing = 0;
  std::string message;
  EXPECT_FALSE(o.Check(&message));
  EXPECT_NE(message.find("min_agreeing"), std::string::npos);
  o = {};
  o.agreement = 0;
  EXPECT_FALSE(o.Check());
  o = {};
  o.max_keyframes = -1;
  EXPECT_FALSE(o.Check());
  o.max_keyframes = 0;  // off
  EXPECT_TRUE(o.Check());
}

}  // namespace
}  // namespace gf
