#include "registration/tracker.h"

#include <gtest/gtest.h>

#include "acquisition/trajectory_metrics.h"
#include "datasets/synth.h"

namespace gf {
namespace {

RgbdFrame SynthDepthFrame(const synth::Scene& scene, const SE3& pose, int index) {
  const synth::SynthFrame f =
      synth::RenderFrame(scene, synth::SynthCamera(), pose, synth::KinectModelOptions{}, 4, index);
  RgbdFrame frame;
  frame.index = index;
  frame.timestamp = index / 30.0;
  ConvertDepth(f.raw_disparity, DepthConvention::KinectV1Raw11Bit(), {}, &frame.depth,
               &frame.hole_mask);
  return frame;
}

TEST(FrameToKeyframeTracker, FollowsTheSyntheticGlassTableTrajectory) {
  synth::SynthOptions options;
  options.frames = 24;
  const synth::Scene scene = synth::Scene::Make("glass-table", 4);
  const std::vector<SE3> poses = synth::MakeTrajectory(scene, options);
  FrameToKeyframeTracker tracker(synth::SynthCamera(), TrackerOptions{});
  Trajectory gt, est;
  for (int i = 0; i < options.frames; ++i) {
    const TrackingResult r = tracker.Track(SynthDepthFrame(scene, poses[i], i));
    EXPECT_NE(r.status, TrackingStatus::kLost) << "frame " << i << ": " << r.BriefReport();
    gt.push_back({i / 30.0, "", poses[i]});
    est.push_back({i / 30.0, "", r.world_from_camera});
  }
  const TrajectoryErrorSummary s = EvaluateTrajectory(gt, est);
  ASSERT_TRUE(s.success);
  // 24 frames, 37 cm of handheld orbit around the table, noisy quantised Kinect depth.
  EXPECT_LT(s.ate_rmse_m, 0.005) << s.BriefReport();
  EXPECT_GT(tracker.keyframes(), 3);
  EXPECT_LT(tracker.keyframes(), options.frames);
}

TEST(FrameToKeyframeTracker, ReportsLossKeepsThePoseAndRecovers) {
  synth::SynthOptions options;
  options.frames = 8;
  const synth::Scene scene = synth::Scene::Make("glass-table", 4);
  const std::vector<SE3> poses = synth::MakeTrajectory(scene, options);
  FrameToKeyframeTracker tracker(synth::SynthCamera(), TrackerOptions{});
  TrackingResult last;
  for (int i = 0; i < 3; ++i) last = tracker.Track(SynthDepthFrame(scene, poses[i], i));
  ASSERT_EQ(last.status, TrackingStatus::kTracking);
  // A frame with no depth at all (lens covered): lost, pose held.
  RgbdFrame blind = SynthDepthFrame(scene, poses[3], 3);
  blind.depth.setTo(0.f);
  const TrackingResult lost = tracker.Track(blind);
  EXPECT_EQ(lost.status, TrackingStatus::kLost);
  EXPECT_LT((lost.world_from_camera.Matrix() - last.world_from_camera.Matrix()).norm(), 1e-12);
  // The blind frame became the keyframe; the next usable frame restarts from a fresh keyframe.
  const TrackingResult after = tracker.Track(SynthDepthFrame(scene, poses[4], 4));
  EXPECT_EQ(after.status, TrackingStatus::kLost);
  const TrackingResult again = tracker.Track(SynthDepthFrame(scene, poses[5], 5));
  EXPECT_EQ(again.status, TrackingStatus::kTracking) << again.BriefReport();
}

}  // namespace
}  // namespace gf
