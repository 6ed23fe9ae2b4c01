#include "pipeline/fill_stage.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "datasets/synth.h"
#include "tests/testing.h"

namespace gf {
namespace {

// Frames 0, 2, ... of a synthetic glass-table capture, with their true poses.
struct Capture {
  std::vector<RgbdFrame> frames;
  std::vector<SE3> poses;
};

Capture Render(int count) {
  synth::SynthOptions options;
  options.frames = 2 * count;
  const synth::Scene scene = synth::Scene::Make("glass-table", 2);
  const std::vector<SE3> poses = synth::MakeTrajectory(scene, options);
  Capture c;
  for (int i = 0; i < 2 * count; i += 2) {
    c.frames.push_back(
        synth::ToRgbdFrame(synth::RenderFrame(scene, synth::SynthCamera(), poses[i], {}, 2, i), i));
    c.poses.push_back(poses[i]);
  }
  return c;
}

// A keyframe whose fill throws (here: a colour image with one channel, which feature detection
// refuses) is skipped with its reason; the others are filled as usual and every keyframe's files
// are written.
TEST(FillStage, AKeyframeThatFailsIsSkippedAndTheRestAreFilled) {
  testing::TempDir dir;
  Capture c = Render(8);
  cv::cvtColor(c.frames[3].color, c.frames[3].color, cv::COLOR_BGR2GRAY);
  FillStageOptions options;
  options.pairs.lookahead = 2;
  FolderRunSink sink(dir.path(), false);
  FillStage stage(synth::SynthCamera(), options, &sink);
  for (size_t i = 0; i < c.frames.size(); ++i) EXPECT_TRUE(stage.Offer(c.frames[i], c.poses[i]));
  ASSERT_NO_THROW(stage.Finish());
  const FillReport report = stage.Report();
  ASSERT_EQ(report.failed_keyframes.size(), 1u) << nlohmann::ordered_json(report).dump(2);
  // In-memory frames without timestamps are named by their index.
  EXPECT_EQ(report.failed_keyframes[0].timestamp, std::to_string(c.frames[3].index));
  EXPECT_FALSE(report.failed_keyframes[0].reason.empty());
  EXPECT_EQ(report.keyframes_filled, 8);
  EXPECT_EQ(report.keyframes_not_filled, 0);
  EXPECT_GT(report.filled_pixels, 0);
  for (const RgbdFrame& f : c.frames)
    EXPECT_TRUE(std::filesystem::exists(
        dir / ("keyframes/" + std::to_string(f.index) + ".depth_filled.png")))
        << f.index;
}

// Cancel() stops the stage between keyframes: what was queued is counted as not filled.
TEST(FillStage, CancelLeavesTheQueuedKeyframesUnfilledAndCounted) {
  testing::TempDir dir;
  const Capture c = Render(6);
  InMemoryRunSink sink;
  FillStage stage(synth::SynthCamera(), {}, &sink);
  for (size_t i = 0; i < c.frames.size(); ++i) stage.Offer(c.frames[i], c.poses[i]);
  stage.Cancel();
  EXPECT_FALSE(stage.Offer(c.frames[0], c.poses[0]));  // stopped: refused and counted
  ASSERT_NO_THROW(stage.Finish());
  const FillReport report = stage.Report();
  EXPECT_EQ(report.keyframes_filled + report.keyframes_not_filled, 7)
      << nlohmann::ordered_json(report).dump(2);
}

// A keyframe offered with its depth moved to the stamp's instant (as the track stage does where
// it models the rolling shutter) is filled from the moved depth, and written with the sensor's
// pixels as measured: every measured pixel as the sensor gave it, fills only in its holes. That
// holds for a keyframe that fails too (here its features: a one-channel colour image).
TEST(FillStage, WrittenKeyframesKeepTheMeasuredDepth) {
  Capture c = Render(6);
  cv::cvtColor(c.frames[2].color, c.frames[2].color, cv::COLOR_BGR2GRAY);
  InMemoryRunSink sink;
  FillStage stage(synth::SynthCamera(), {}, &sink);
  for (size_t i = 0; i < c.frames.size(); ++i) {
    RgbdFrame placed = c.frames[i];
    placed.depth = c.frames[i].depth * 1.004;  // moved by a few millimetres
    EXPECT_TRUE(stage.Offer(placed, c.poses[i], static_cast<int>(i), c.frames[i].depth));
  }
  ASSERT_NO_THROW(stage.Finish());
  ASSERT_EQ(sink.keyframes.size(), c.frames.size());
  long filled = 0;
  for (const RgbdFrame& f : c.frames) {
    const InMemoryRunSink::Keyframe& k = sink.keyframes.at(std::to_string(f.index));
    const cv::Mat measured = f.hole_mask == 0;
    EXPECT_EQ(cv::norm(k.fill.filled_depth, f.depth, cv::NORM_INF, measured), 0.0) << f.index;
    EXPECT_EQ(cv::norm(k.frame.depth, f.depth, cv::NORM_INF), 0.0) << f.index;
    EXPECT_EQ(cv::countNonZero(k.fill.fill_mask & measured), 0) << f.index;
    filled += cv::countNonZero(k.fill.fill_mask);
  }
  EXPECT_GT(filled, 0);
}

}  // namespace
}  // namespace gf
