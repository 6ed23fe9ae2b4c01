#include "registration/tracker.h"

#include <gtest/gtest.h>

#include <cstdio>

#include "acquisition/trajectory_metrics.h"
#include "datasets/synth.h"

namespace gf {
namespace {

// The synthetic frames are rendered at one pose each.
TrackerOptions GlobalShutter() { return ForSensor(TrackerOptions{}, synth::SynthCameraFile()); }

// `frames` tracked from the first on the synthetic camera; ATE against poses[frame.index].
struct TrackedRun {
  bool evaluated = false;  // the trajectory could be scored
  double ate_m = 0;
  int lost = 0;          // frames reported lost
  int without_pose = 0;  // frames without a pose (lost or restarted)
  int keyframes = 0;     // the tracker's keyframes at the end
};
TrackedRun TrackFrames(const std::vector<RgbdFrame>& frames, const std::vector<SE3>& poses,
                       const TrackerOptions& options) {
  FrameToKeyframeTracker tracker(synth::SynthCamera(), options);
  Trajectory gt, est;
  TrackedRun run;
  for (const RgbdFrame& f : frames) {
    const TrackingResult r = tracker.Track(f);
    run.lost += r.status == TrackingStatus::kLost;
    run.without_pose += !r.has_pose();
    gt.push_back({f.timestamp, "", poses[f.index]});
    est.push_back({f.timestamp, "", r.world_from_camera});
  }
  const TrajectoryErrorSummary summary = EvaluateTrajectory(gt, est);
  run.evaluated = summary.success;
  run.ate_m = summary.ate_rmse_m;
  run.keyframes = tracker.keyframes();
  return run;
}

RgbdFrame SynthDepthFrame(const synth::Scene& scene, const SE3& pose, int index) {
  const synth::SynthFrame f =
      synth::RenderFrame(scene, synth::SynthCamera(), pose, synth::KinectModelOptions{}, 4, index);
  RgbdFrame frame = synth::ToRgbdFrame(f, index);
  frame.timestamp = index / 30.0;
  return frame;
}

TEST(FrameToKeyframeTracker, FollowsTheSyntheticGlassTableTrajectory) {
  synth::SynthOptions options;
  options.frames = 24;
  const synth::Scene scene = synth::Scene::Make("glass-table", 4);
  const std::vector<SE3> poses = synth::MakeTrajectory(scene, options);
  std::vector<RgbdFrame> frames;
  for (int i = 0; i < options.frames; ++i) frames.push_back(SynthDepthFrame(scene, poses[i], i));
  const TrackedRun run = TrackFrames(frames, poses, GlobalShutter());
  ASSERT_TRUE(run.evaluated);
  EXPECT_EQ(run.lost, 0);
  // 24 frames, 37 cm of handheld orbit around the table, noisy quantised Kinect depth.
  EXPECT_LT(run.ate_m, 0.005);
  EXPECT_GT(run.keyframes, 3);
  EXPECT_LT(run.keyframes, options.frames);
}

// Smooth motion, then a sudden jump of ten frames (about 16 cm and 7 degrees) that the
// constant-velocity prediction does not foresee: beyond dense ICP's basin (see icp_test), while
// SURF + RANSAC put ICP back into it.
TEST(FrameToKeyframeTracker, FeaturesCarryASuddenJump) {
  synth::SynthOptions options;
  options.frames = 20;
  const synth::Scene scene = synth::Scene::Make("glass-table", 4);
  const std::vector<SE3> poses = synth::MakeTrajectory(scene, options);
  std::vector<RgbdFrame> frames;
  for (int i : {0, 1, 2, 3, 4, 14, 15, 16}) frames.push_back(SynthDepthFrame(scene, poses[i], i));
  auto ate = [&](bool use_features, int* lost) {
    TrackerOptions tracker_options = GlobalShutter();
    tracker_options.use_features = use_features;
    const TrackedRun run = TrackFrames(frames, poses, tracker_options);
    *lost = run.lost;
    return run.ate_m;
  };
  int lost_with = 0, lost_without = 0;
  const double with_features = ate(true, &lost_with);
  const double without = ate(false, &lost_without);
  std::printf("sudden jump: ATE with features %.4f m (%d lost), dense only %.4f m (%d lost)\n",
              with_features, lost_with, without, lost_without);
  EXPECT_EQ(lost_with, 0);
  EXPECT_LT(with_features, 0.01);
  EXPECT_GT(without, 2 * with_features)
      << "dense only: " << without << " m, " << lost_without << " lost";
}

TEST(FrameToKeyframeTracker, ReportsLossKeepsThePoseAndRecovers) {
  synth::SynthOptions options;
  options.frames = 8;
  const synth::Scene scene = synth::Scene::Make("glass-table", 4);
  const std::vector<SE3> poses = synth::MakeTrajectory(scene, options);
  FrameToKeyframeTracker tracker(synth::SynthCamera(), GlobalShutter());
  TrackingResult last;
  for (int i = 0; i < 3; ++i) last = tracker.Track(SynthDepthFrame(scene, poses[i], i));
  ASSERT_EQ(last.status, TrackingStatus::kTracking);
  // A frame with no depth at all (lens covered): no pose; without a relocaliser tracking restarts
  // there at once, at the last good pose.
  RgbdFrame blind = SynthDepthFrame(scene, poses[3], 3);
  blind.depth.setTo(0.f);
  const TrackingResult lost = tracker.Track(blind);
  EXPECT_EQ(lost.status, TrackingStatus::kRestarted);
  EXPECT_FALSE(lost.has_pose());
  EXPECT_TRUE(lost.new_keyframe);
  EXPECT_LT((lost.world_from_camera.Matrix() - last.world_from_camera.Matrix()).norm(), 1e-12);
  // The blind frame became the keyframe; the next usable frame restarts from a fresh keyframe.
  const TrackingResult after = tracker.Track(SynthDepthFrame(scene, poses[4], 4));
  EXPECT_FALSE(after.has_pose());
  const TrackingResult again = tracker.Track(SynthDepthFrame(scene, poses[5], 5));
  EXPECT_EQ(again.status, TrackingStatus::kTracking) << again.BriefReport();
}

// Tracking undistorts the frames it aligns into images of its own: the caller's frame (shared with
// the fill and the fusion) stays as it was.
TEST(FrameToKeyframeTracker, LeavesTheCallersFrameAsItWas) {
  const synth::Scene scene = synth::Scene::Make("glass-table", 4);
  synth::SynthOptions options;
  options.frames = 2;
  const std::vector<SE3> poses = synth::MakeTrajectory(scene, options);
  Camera camera = synth::SynthCamera();
  camera.distortion = {0.26, -0.95, -0.005, 0.003, 1.16, 0, 0, 0};  // TUM fr1's lens
  FrameToKeyframeTracker tracker(camera, GlobalShutter());
  for (int i = 0; i < 2; ++i) {
    const RgbdFrame frame = SynthDepthFrame(scene, poses[i], i);
    const cv::Mat color = frame.color.clone(), depth = frame.depth.clone(),
                  holes = frame.hole_mask.clone();
    const TrackingResult r = tracker.Track(frame);
    EXPECT_EQ(cv::norm(frame.color, color, cv::NORM_INF), 0);
    EXPECT_EQ(cv::norm(frame.depth, depth, cv::NORM_INF), 0);
    EXPECT_EQ(cv::norm(frame.hole_mask, holes, cv::NORM_INF), 0);
    EXPECT_GT(cv::norm(r.tracked_depth, depth, cv::NORM_INF), 0);  // undistorted: not the same
  }
}

SE3 Between(const SE3& a, const SE3& b, double s) {
  return a * SE3::Exp(s * (a.Inverse() * b).Log());
}

// A frame as a rolling-shutter sensor read out over one frame period sees it: the rows of band k
// (of `bands`) from where the camera is at that band's time, between the previous frame's stamp
// and this one's; the frame is stamped at its last row.
RgbdFrame RollingShutterFrame(const synth::Scene& scene, const std::vector<SE3>& poses, int index,
                              int bands) {
  synth::SynthFrame composite;
  for (int k = 0; k < bands; ++k) {
    const double s = (k + 0.5) / bands;  // of the way from the previous stamp to this one
    const SE3 pose = index == 0 ? poses[0] : Between(poses[index - 1], poses[index], s);
    const synth::SynthFrame f = synth::RenderFrame(scene, synth::SynthCamera(), pose,
                                                   synth::KinectModelOptions{}, 4, index);
    if (k == 0) composite = f;
    const cv::Rect rows(0, f.color.rows * k / bands, f.color.cols, f.color.rows / bands);
    for (auto [from, to] : {std::pair{&f.color, &composite.color},
                            {&f.raw_disparity, &composite.raw_disparity},
                            {&f.true_depth, &composite.true_depth},
                            {&f.visible_depth, &composite.visible_depth},
                            {&f.label, &composite.label},
                            {&f.hole_reason, &composite.hole_reason}})
      (*from)(rows).copyTo((*to)(rows));
  }
  RgbdFrame frame = synth::ToRgbdFrame(composite, index);
  frame.timestamp = index / 30.0;
  return frame;
}

// The handheld orbit at 1.6 cm per frame, seen through a rolling shutter read out over the frame
// period: tracking that models the readout follows the camera at its stamps more closely than
// tracking that takes each frame as one instant.
TEST(FrameToKeyframeTracker, ModelsTheDepthSensorsRollingShutter) {
  synth::SynthOptions options;
  options.frames = 12;
  const synth::Scene scene = synth::Scene::Make("glass-table", 4);
  const std::vector<SE3> poses = synth::MakeTrajectory(scene, options);
  std::vector<RgbdFrame> frames;
  for (int i = 0; i < options.frames; ++i)
    frames.push_back(RollingShutterFrame(scene, poses, i, 8));
  auto ate = [&](double readout_s) {
    TrackerOptions tracker_options;
    tracker_options.depth_readout_s = readout_s;
    const TrackedRun run = TrackFrames(frames, poses, tracker_options);
    EXPECT_EQ(run.without_pose, 0) << "readout " << readout_s << " s";
    return run.ate_m;
  };
  const double modelled = ate(1.0 / 30), ignored = ate(0);
  std::printf("rolling shutter: ATE %.4f m with the readout modelled, %.4f m without\n", modelled,
              ignored);
  EXPECT_LT(modelled, 0.6 * ignored);
  EXPECT_LT(modelled, 0.004);
}

}  // namespace
}  // namespace gf
