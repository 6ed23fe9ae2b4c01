#include "pipeline/reconstruction.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <atomic>
#include <chrono>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "acquisition/errors.h"
#include "acquisition/trajectory_metrics.h"
#include "datasets/synth.h"
#include "eval/fill_truth.h"
#include "tests/same_run.h"

namespace gf {
namespace {

// A synthetic glass-table capture in memory, with its ground truth: the frames as a source would
// deliver them, the true poses, and per frame what colour sees (through clear glass: the
// background) and the material.
struct Capture {
  CameraFile camera;
  std::vector<RgbdFrame> frames;
  Trajectory truth;
  std::vector<cv::Mat> visible_depth, label;
};

const Capture& GlassTable() {
  static const Capture capture = [] {
    Capture c;
    c.camera = synth::SynthCameraFile();
    synth::SynthOptions options;
    options.frames = 30;
    options.seed = 4;
    const synth::Scene scene = synth::Scene::Make("glass-table", options.seed);
    const std::vector<SE3> poses = synth::MakeTrajectory(scene, options);
    for (int i = 0; i < options.frames; ++i) {
      const synth::SynthFrame f =
          synth::RenderFrame(scene, c.camera.camera, poses[i], options.kinect, options.seed, i);
      RgbdFrame frame = synth::ToRgbdFrame(f, i);
      frame.timestamp = i / options.fps;
      c.frames.push_back(frame);
      c.truth.push_back({frame.timestamp, "", poses[i]});
      c.visible_depth.push_back(f.visible_depth);
      c.label.push_back(f.label);
    }
    return c;
  }();
  return capture;
}

// The written keyframes' fill per material against the truth (eval/fill_truth.h).
FillScore ScoreByMaterial(const Capture& c, const InMemoryRunSink& sink) {
  FillScore score;
  for (const auto& [name, k] : sink.keyframes) {
    const int i = k.frame.index;
    cv::Mat filled, truth;
    k.fill.filled_depth.convertTo(filled, CV_64F);
    c.visible_depth[i].convertTo(truth, CV_64F);
    ScoreKeyframeFill(filled, k.frame.hole_mask, c.label[i], truth, cv::Mat(), cv::Mat(), &score);
  }
  return score;
}

// The fill's surfels' distances to the true surface along their normals (1 m where none lies
// within 5 cm), in the run's frame moved by the first true pose; sorted.
std::vector<double> FillSurfelErrors(const Capture& c, const std::vector<Surfel>& map) {
  const synth::Scene scene = synth::Scene::Make("glass-table", 4);
  const SE3 world_from_run = c.truth[0].world_from_camera;
  std::vector<double> fill_errors;
  for (const Surfel& surfel : map) {
    if (surfel.source != static_cast<uint8_t>(DepthSource::kStereo)) continue;
    const Eigen::Vector3d p = world_from_run * surfel.position.cast<double>();
    const Eigen::Vector3d n = world_from_run.RotationMatrix() * surfel.normal.cast<double>();
    synth::Hit hit;
    fill_errors.push_back(
        scene.Intersect(p + 0.05 * n, -n, 0.0, 0.1, false, &hit) ? std::abs(hit.t - 0.05) : 1.0);
  }
  std::sort(fill_errors.begin(), fill_errors.end());
  return fill_errors;
}

TEST(Reconstruction, TracksAndFillsTheSyntheticGlassTable) {
  const Capture& c = GlassTable();
  InMemoryFrameSource source(c.camera, c.frames);
  InMemoryRunSink sink;
  int progress_calls = 0;
  ReconstructionCallbacks callbacks;
  callbacks.progress = [&](const ReconstructionProgress& p) {
    ++progress_calls;
    EXPECT_EQ(p.total, 30);
  };
  const ReconstructionSummary s = Reconstruction({}).Run(source, &sink, callbacks);
  std::printf("%s\n", s.BriefReport().c_str());
  EXPECT_TRUE(s.complete);
  EXPECT_EQ(s.frames, 30);
  EXPECT_EQ(s.lost, 0);
  EXPECT_GT(progress_calls, 0);
  // Tracking: within a centimetre of the true trajectory.
  ASSERT_EQ(sink.trajectory.size(), 30u);
  const TrajectoryErrorSummary ate = EvaluateTrajectory(c.truth, sink.trajectory);
  ASSERT_TRUE(ate.success);
  EXPECT_LT(ate.ate_rmse_m, 0.01);
  // The report says what happened.
  const nlohmann::ordered_json& r = sink.report;
  EXPECT_EQ(r, s.report);
  EXPECT_TRUE(r["complete"].get<bool>());
  EXPECT_EQ(r["frames"], 30);
  EXPECT_EQ(r["keyframes"], s.keyframes);
  EXPECT_EQ(r["fill"]["keyframes_filled"], s.keyframes);
  EXPECT_EQ(sink.keyframes.size(), static_cast<size_t>(s.keyframes));
  EXPECT_TRUE(r["fill"]["failed_keyframes"].empty());
  int paths = 0;
  for (const auto& [path, count] : r["fill"]["pair_paths"].items()) paths += count.get<int>();
  EXPECT_EQ(paths, r["fill"]["keyframes_paired"].get<int>());
  EXPECT_GT(r["fill"]["pair_paths"]["rectified_sgbm"].get<int>(), 0);  // the scene orbits sideways
  // Fills another keyframe saw through are counted per keyframe (hole pixels) and in total.
  int seen_through = 0;
  for (const auto& k : r["fill"]["per_keyframe"]) {
    seen_through += k["seen_through_pixels"].get<int>();
    EXPECT_GE(k["seen_through_pixels"].get<int>(), 0);
    EXPECT_LE(k["seen_through_pixels"].get<int>(), k["hole_pixels"].get<int>());
  }
  EXPECT_EQ(seen_through, r["fill"]["seen_through_pixels"].get<int>());
  // The fill: most of the glossy, dark and textured-glass holes, nearly all within 3%; measured
  // pixels never change.
  const FillScore m = ScoreByMaterial(c, sink);
  for (int material : {1, 2, 3}) {
    SCOPED_TRACE(MaterialName(material));
    const double fill_rate = m.Rate(m.filled, material);
    const double good_share =
        m.filled[material] ? double(m.good[material]) / m.filled[material] : 0.0;
    std::printf("%s: %zu holes, %.1f%% filled, %.1f%% of them within 3%%\n",
                MaterialName(material).c_str(), m.holes[material], 100 * fill_rate,
                100 * good_share);
    EXPECT_GT(fill_rate, 0.6);
    EXPECT_GT(good_share, 0.9);
  }
  for (const auto& [name, k] : sink.keyframes)
    EXPECT_EQ(cv::norm(k.fill.filled_depth, k.frame.depth, cv::NORM_INF, k.frame.hole_mask == 0),
              0.0)
        << name;
  // The surfel map: written, with the sensor's surfels and the confirmed fills', the fills on the
  // true surfaces (distance along their normal, in the run's frame moved by the first true pose).
  ASSERT_TRUE(sink.map_written);
  EXPECT_EQ(static_cast<long>(sink.map.size()), s.surfels);
  EXPECT_EQ(r["surfels"]["count"], s.surfels);
  EXPECT_GT(r["surfels"]["by_source"]["sensor"].get<long>(), 10000);
  EXPECT_GT(r["surfels"]["by_source"]["stereo_fill"].get<long>(), 500);
  const std::vector<double> fill_errors = FillSurfelErrors(c, sink.map);
  ASSERT_FALSE(fill_errors.empty());
  EXPECT_LT(fill_errors[fill_errors.size() / 2], 0.01);
}

// At the end of the run, each keyframe's holes that its own fill left empty take the final map's
// fills seen from it: only hole pixels, nearly all within 3% of what colour sees there (the
// background through clear glass), and the report counts them.
TEST(Reconstruction, TheMapCompletesEachKeyframeFromItsFills) {
  const Capture& c = GlassTable();
  InMemoryFrameSource source(c.camera, c.frames);
  InMemoryRunSink sink;
  const ReconstructionSummary s = Reconstruction({}).Run(source, &sink);
  ASSERT_TRUE(s.complete);
  ASSERT_TRUE(sink.report.fill && sink.report.fill->model_completion);
  const ModelCompletionReport& record = *sink.report.fill->model_completion;
  long completed = 0, good = 0, outside_holes = 0, in_shadows = 0;
  std::vector<std::pair<float, bool>> confidence_good;  // per completed pixel
  for (const auto& [name, k] : sink.keyframes) {
    if (k.model_fill.empty()) continue;
    const int i = k.frame.index;
    for (int y = 0; y < k.model_fill.rows; ++y)
      for (int x = 0; x < k.model_fill.cols; ++x) {
        if (!k.model_fill.at<uint8_t>(y, x)) continue;
        ++completed;
        outside_holes += k.frame.hole_mask.at<uint8_t>(y, x) == 0;
        in_shadows +=
            k.frame.hole_mask.at<uint8_t>(y, x) == static_cast<uint8_t>(HoleCode::kShadow);
        const double z = k.fill.filled_depth.at<float>(y, x),
                     t = c.visible_depth[i].at<float>(y, x);
        const bool right = t > 0 && std::abs(z - t) <= 0.03 * t;
        good += right;
        const float confidence = k.fill.confidence.at<float>(y, x);
        ASSERT_TRUE(confidence > 0.f && confidence <= 1.f) << confidence << " at " << x << ", " << y;
        confidence_good.emplace_back(confidence, right);
      }
  }
  // The confidence written for the completed pixels predicts their error: the upper half is
  // right more often than the lower (measured 97.5% against 86.0%).
  std::sort(confidence_good.begin(), confidence_good.end());
  const size_t half = confidence_good.size() / 2;
  double lower = 0, upper = 0;
  for (size_t i = 0; i < confidence_good.size(); ++i)
    (i < half ? lower : upper) += confidence_good[i].second;
  lower /= std::max<size_t>(half, 1);
  upper /= std::max<size_t>(confidence_good.size() - half, 1);
  std::printf("model completion: %ld pixels of %d keyframes, %.1f%% within 3%% (upper half of "
              "the confidence %.1f%%, lower %.1f%%)\n",
              completed, record.keyframes, completed ? 100.0 * good / completed : 0.0,
              100 * upper, 100 * lower);
  EXPECT_GT(upper, lower + 0.05);
  EXPECT_EQ(completed, record.pixels);
  EXPECT_GT(completed, 200);
  EXPECT_EQ(outside_holes, 0);
  EXPECT_EQ(in_shadows, 0);  // the near object's fill spread past its edge would land there
  // Measured 91.1% with every fill the map offered (AMD EPYC, 2 cores), the same on every run
  // since fills join the map at fixed points of the sequence (before, it varied between 89.8%
  // and 91.2% from run to run on an Intel machine); 91.7% now that surfaces seen from
  // behind or hidden by the keyframe's own nearer depth are left out. The bound leaves room for
  // the few tenths that another CPU's SIMD paths (OpenCV's dispatch) may move it, not for a
  // completion that is worse.
  EXPECT_GT(good, 0.88 * completed);
  EXPECT_FALSE(record.stopped);
}

// A sink whose keyframe writes take `delay`: the fill stage falls far behind tracking and fusion.
class SlowKeyframeSink : public InMemoryRunSink {
 public:
  explicit SlowKeyframeSink(std::chrono::milliseconds delay) : delay_(delay) {}
  void WriteKeyframe(const std::string& name, const RgbdFrame& frame,
                     const CarriedFillResult& fill) override {
    std::this_thread::sleep_for(delay_);
    InMemoryRunSink::WriteKeyframe(name, frame, fill);
  }

 private:
  std::chrono::milliseconds delay_;
};

// A recorded capture gives the same outputs on every run, however fast each stage happens to be:
// fills and loop corrections join the map at fixed points of the frame sequence. One run with
// the fill held back (each keyframe's write 300 ms late), one with tracking held back (each
// frame read 150 ms late), every output compared value for value.
TEST(Reconstruction, ARecordedCaptureGivesTheSameOutputsHoweverFastEachStageRuns) {
  const Capture& c = GlassTable();
  testing::PacedSource slow_source(c.camera, c.frames, std::chrono::milliseconds(150));
  InMemoryRunSink first;
  const ReconstructionSummary a = Reconstruction({}).Run(slow_source, &first);
  InMemoryFrameSource source(c.camera, c.frames);
  SlowKeyframeSink second(std::chrono::milliseconds(300));
  const ReconstructionSummary b = Reconstruction({}).Run(source, &second);
  ASSERT_TRUE(a.complete && b.complete);
  EXPECT_GT(a.filled_pixels, 0);
  ASSERT_TRUE(first.report.fill && first.report.fill->model_completion);
  EXPECT_GT(first.report.fill->model_completion->pixels, 0);
  testing::ExpectSameRun(first, second);
}

// A keyframe the fill cannot take (its colour has an alpha channel, which the stereo refuses) is
// skipped and reported; tracking and the other keyframes' fills go on.
TEST(Reconstruction, AFillFailureIsContained) {
  Capture c = GlassTable();
  cv::cvtColor(c.frames[0].color, c.frames[0].color, cv::COLOR_BGR2BGRA);  // the first keyframe
  InMemoryFrameSource source(c.camera, c.frames);
  InMemoryRunSink sink;
  const ReconstructionSummary s = Reconstruction({}).Run(source, &sink);
  EXPECT_TRUE(s.complete);
  EXPECT_EQ(s.frames, 30);
  ASSERT_TRUE(sink.report.fill);
  const std::vector<FailedKeyframe>& failed = sink.report.fill->failed_keyframes;
  ASSERT_EQ(failed.size(), 1u) << nlohmann::ordered_json(*sink.report.fill).dump(2);
  EXPECT_EQ(failed[0].timestamp, "0");
  EXPECT_EQ(sink.report.fill->keyframes_filled, s.keyframes);
  EXPECT_GT(s.filled_pixels, 0);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_NE(s.warnings[0].find("keyframe 0 not filled"), std::string::npos);
}

// A frame that cannot be read ends the run: the frames before it are kept and reported, the
// keyframes tracked so far are filled, and the error reaches the caller.
class FailingSource : public InMemoryFrameSource {
 public:
  FailingSource(CameraFile camera, std::vector<RgbdFrame> frames, int fail_at)
      : InMemoryFrameSource(std::move(camera), std::move(frames)), fail_at_(fail_at) {}
  bool Next(RgbdFrame* frame) override {
    if (delivered_++ == fail_at_) throw InputError("frame.png", "cannot decode depth image");
    return InMemoryFrameSource::Next(frame);
  }

 private:
  int fail_at_, delivered_ = 0;
};

TEST(Reconstruction, AnUnreadableFrameStopsTheRunWithHonestOutputs) {
  const Capture& c = GlassTable();
  FailingSource source(c.camera, c.frames, 12);
  InMemoryRunSink sink;
  EXPECT_THROW(Reconstruction({}).Run(source, &sink), InputError);
  const nlohmann::ordered_json& r = sink.report;
  EXPECT_FALSE(r["complete"].get<bool>());
  EXPECT_EQ(r["stopped_because"], "frame.png: cannot decode depth image");
  EXPECT_EQ(r["frames"], 12);
  EXPECT_EQ(sink.trajectory.size(), 12u);
  EXPECT_EQ(r["fill"]["keyframes_filled"], r["keyframes"]);
}

// A stop request (Ctrl-C in the command line) ends the run early with what it has.
TEST(Reconstruction, AStopRequestEndsTheRunEarly) {
  const Capture& c = GlassTable();
  InMemoryFrameSource source(c.camera, c.frames);
  InMemoryRunSink sink;
  int frames_seen = 0;
  ReconstructionCallbacks callbacks;
  callbacks.progress = [&](const ReconstructionProgress& p) { frames_seen = p.frames; };
  callbacks.stop = [&]() -> std::string { return frames_seen >= 5 ? "stopped by the test" : ""; };
  const ReconstructionSummary s = Reconstruction({}).Run(source, &sink, callbacks);
  EXPECT_FALSE(s.complete);
  EXPECT_EQ(s.stopped_because, "stopped by the test");
  EXPECT_FALSE(sink.report.complete);
  EXPECT_EQ(sink.report.stopped_because, "stopped by the test");
  EXPECT_GE(s.frames, 5);
  EXPECT_EQ(sink.trajectory.size(), static_cast<size_t>(s.frames));
  ASSERT_TRUE(sink.report.fill);
  EXPECT_LE(sink.report.fill->keyframes_filled + sink.report.fill->keyframes_not_filled,
            s.keyframes);
}

// A sink that records the order of what is written, and the "complete" of every report.
class RecordingSink : public InMemoryRunSink {
 public:
  void WriteKeyframe(const std::string& name, const RgbdFrame& frame,
                     const CarriedFillResult& fill) override {
    Note("keyframe");
    InMemoryRunSink::WriteKeyframe(name, frame, fill);
  }
  void WriteTrajectory(const Trajectory& trajectory) override {
    Note("trajectory");
    InMemoryRunSink::WriteTrajectory(trajectory);
  }
  void WriteReport(const RunReport& report) override {
    Note("report");
    std::lock_guard<std::mutex> lock(mutex_);
    reports_complete.push_back(report.complete);
    InMemoryRunSink::WriteReport(report);
  }
  void WriteMap(const std::vector<Surfel>& surfels) override {
    Note("map");
    InMemoryRunSink::WriteMap(surfels);
  }
  int CompleteKeyframe(const std::string& name, const MapCompletion& offer) override {
    Note("completion");
    ++completed_calls;
    return InMemoryRunSink::CompleteKeyframe(name, offer);
  }
  std::vector<std::string> order;
  std::vector<bool> reports_complete;
  std::atomic<int> completed_calls{0};

 private:
  void Note(const std::string& what) {
    std::lock_guard<std::mutex> lock(mutex_);
    order.push_back(what);
  }
  std::mutex mutex_;
};

// The capture's first n frames (sharing their pixels with it: replace an image, never write to it).
std::vector<RgbdFrame> FirstFrames(int n) {
  const Capture& c = GlassTable();
  return std::vector<RgbdFrame>(c.frames.begin(), c.frames.begin() + n);
}

// report.json is the last file written, and until then the report says the run is not complete;
// the finish callback runs before the last report, which carries what it threw as a warning.
TEST(Reconstruction, TheReportIsWrittenLastAndSaysCompleteOnlyThen) {
  InMemoryFrameSource source(GlassTable().camera, FirstFrames(12));
  RecordingSink sink;
  ReconstructionCallbacks callbacks;
  bool finished = false;
  callbacks.finish = [&](const RunReport& report) {
    EXPECT_TRUE(report.complete);
    EXPECT_GT(sink.completed_calls.load(), 0);  // after the completion from the map
    finished = true;
    throw std::runtime_error("report.html not written: a test");
  };
  const ReconstructionSummary s = Reconstruction({}).Run(source, &sink, callbacks);
  ASSERT_TRUE(s.complete);
  EXPECT_TRUE(finished);
  ASSERT_FALSE(sink.order.empty());
  EXPECT_EQ(sink.order.back(), "report");
  ASSERT_GE(sink.reports_complete.size(), 2u);
  for (size_t i = 0; i + 1 < sink.reports_complete.size(); ++i)
    EXPECT_FALSE(sink.reports_complete[i]) << "report " << i << " said complete too early";
  EXPECT_TRUE(sink.reports_complete.back());
  ASSERT_FALSE(sink.report.warnings.empty());
  EXPECT_EQ(sink.report.warnings.back(), "report.html not written: a test");
}

// A stop request while the keyframes are being completed from the map: not complete, and the
// report says it stopped during the completion.
TEST(Reconstruction, AStopDuringTheMapCompletionLeavesTheRunIncomplete) {
  InMemoryFrameSource source(GlassTable().camera, FirstFrames(12));
  RecordingSink sink;
  ReconstructionCallbacks callbacks;
  callbacks.stop = [&]() -> std::string {
    return sink.completed_calls >= 1 ? "stopped by the test" : "";
  };
  bool finished = false;
  callbacks.finish = [&](const RunReport&) { finished = true; };
  const ReconstructionSummary s = Reconstruction({}).Run(source, &sink, callbacks);
  EXPECT_FALSE(s.complete);
  EXPECT_FALSE(s.refused);
  EXPECT_FALSE(finished);
  EXPECT_EQ(s.stopped_because, "stopped by the test");
  EXPECT_EQ(s.stopped_during.rfind("map completion", 0), 0u) << s.stopped_during;
  EXPECT_FALSE(sink.report.complete);
  EXPECT_EQ(sink.report.stopped_during, s.stopped_during);
  ASSERT_TRUE(sink.report.fill && sink.report.fill->model_completion);
  EXPECT_TRUE(sink.report.fill->model_completion->stopped);
  for (bool complete : sink.reports_complete) EXPECT_FALSE(complete);
}

// Runs whose result is not usable are refused: not complete, with the reason. Tracking lost on
// most frames (accepted with allow_lost):
TEST(Reconstruction, ARunThatLosesTrackingIsRefusedUnlessAllowed) {
  std::vector<RgbdFrame> blind = FirstFrames(8);
  for (RgbdFrame& f : blind) {
    f.depth = cv::Mat(f.depth.size(), CV_32FC1, cv::Scalar(0));  // (= Mat::zeros would write
                                                                  // into the shared pixels)
    f.hole_mask = cv::Mat(f.hole_mask.size(), CV_8UC1, cv::Scalar(1));
  }
  ReconstructionOptions options;
  options.fill = false;
  options.fusion = false;
  InMemoryFrameSource source(GlassTable().camera, blind);
  InMemoryRunSink sink;
  const ReconstructionSummary s = Reconstruction(options).Run(source, &sink);
  EXPECT_TRUE(s.refused && !s.complete);
  EXPECT_NE(s.stopped_because.find("tracking was lost on 7 of 8 frames"), std::string::npos)
      << s.stopped_because;
  EXPECT_FALSE(sink.report.complete);
  options.allow_lost = true;  // accepted, with a warning
  InMemoryFrameSource again(GlassTable().camera, blind);
  EXPECT_TRUE(Reconstruction(options).Run(again, &sink).complete);
}

// ... an empty map (here: the map keeps nothing farther than 0.31 m; the scene is 1-3 m away):
TEST(Reconstruction, AnEmptyMapIsRefused) {
  ReconstructionOptions options;
  options.fill = false;
  options.fusion_options.fusion.max_depth_m = 0.31;
  InMemoryFrameSource source(GlassTable().camera, FirstFrames(8));
  InMemoryRunSink sink;
  const ReconstructionSummary s = Reconstruction(options).Run(source, &sink);
  EXPECT_TRUE(s.refused && !s.complete);
  EXPECT_NE(s.stopped_because.find("the map is empty"), std::string::npos) << s.stopped_because;
}

// ... a fill that failed on every keyframe (their colour has an alpha channel, which the stereo
// refuses):
TEST(Reconstruction, AFillThatFailsOnEveryKeyframeIsRefused) {
  std::vector<RgbdFrame> frames = FirstFrames(8);
  for (RgbdFrame& f : frames) {
    cv::Mat bgra;  // a new image: the frames share their pixels with the capture's
    cv::cvtColor(f.color, bgra, cv::COLOR_BGR2BGRA);
    f.color = bgra;
  }
  InMemoryFrameSource source(GlassTable().camera, frames);
  InMemoryRunSink sink;
  const ReconstructionSummary s = Reconstruction({}).Run(source, &sink);
  EXPECT_TRUE(s.refused && !s.complete);
  EXPECT_NE(s.stopped_because.find("the fill failed on every keyframe"), std::string::npos)
      << s.stopped_because;
}

TEST(Reconstruction, RefusesBadOptions) {
  ReconstructionOptions options;
  options.first_frame = 5;
  options.end_frame = 5;
  EXPECT_THROW(Reconstruction{options}, InputError);
  options = {};
  options.fill_options.queue_capacity = 0;
  EXPECT_THROW(Reconstruction{options}, InputError);
  options.fill = false;  // the fill's options do not matter then
  EXPECT_NO_THROW(Reconstruction{options});
}

}  // namespace
}  // namespace gf
