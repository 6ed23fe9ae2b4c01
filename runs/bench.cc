#include "runs/bench.h"

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>
#include <optional>
#include <thread>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/progress.h"
#include "acquisition/run_layout.h"
#include "acquisition/stats.h"
#include "acquisition/trajectory.h"
#include "acquisition/trajectory_metrics.h"
#include "fill/keyframe_filler.h"
#include "fill/stereo_fill.h"
#include "pipeline/run_reader.h"
#include "pipeline/settings.h"
#include "pipeline/timing.h"
#include "registration/tracker.h"
#include "runs/bench_fusion.h"
#include "surfels/fusion.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

using Clock = std::chrono::steady_clock;

struct MethodResult {
  std::string name;
  Trajectory trajectory;
  std::vector<double> ms;
  int failures = 0;
};

nlohmann::ordered_json Summarise(const MethodResult& m, const Trajectory* gt) {
  double total = 0;
  for (double v : m.ms) total += v;
  nlohmann::ordered_json j;
  j["method"] = m.name;
  j["frames"] = m.trajectory.size();
  j["median_ms"] = Median(m.ms);
  j["fps"] = total > 0 ? 1000.0 * m.ms.size() / total : 0.0;
  j["failed_frames"] = m.failures;
  if (gt) {
    const TrajectoryErrorSummary s = EvaluateTrajectory(*gt, m.trajectory);
    j["ate_rmse_m"] = s.success ? nlohmann::json(s.ate_rmse_m) : nlohmann::json(nullptr);
    j["rpe_trans_rmse_m"] =
        s.success ? nlohmann::json(s.rpe_trans_rmse_m) : nlohmann::json(nullptr);
  }
  return j;
}

Eigen::Matrix4d ToEigen(const cv::Mat& m) {
  Eigen::Matrix4d e;
  cv::cv2eigen(m, e);
  return e;
}

// OpenCV's StereoSGBM alone on the pair as our fill rectified it (the dense-stereo step without
// our range, checks and validation): the full num_disparities from 0 and the other SGBM settings
// of `o`. Milliseconds, or nothing when such a search does not fit the rectified image.
std::optional<double> TimeOpenCvSgbm(const RgbdFrame& key1, const RgbdFrame& key2,
                                     const Camera& camera, const SgbmRectification& rect,
                                     const SgbmOptions& o) {
  const auto t0 = Clock::now();
  const RectifiedImages images = RectifyImages(rect, key1, key2, camera);
  const int bs = o.block_size;
  if (!SgbmParametersFit(images.left.cols, images.left.rows, 0, o.num_disparities, bs)) return {};
  cv::Mat disparity;
  cv::StereoSGBM::create(0, o.num_disparities, bs, 8 * bs * bs, 32 * bs * bs,
                         static_cast<int>(std::lround(o.max_lr_difference_px)), 63,
                         o.uniqueness_ratio, o.speckle_window, o.speckle_range,
                         cv::StereoSGBM::MODE_SGBM_3WAY)
      ->compute(images.left, images.right, disparity);
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Stereo hole filling per keyframe pair on one core (see BenchOptions::fill_every), by the
// KeyframeFiller that the pipeline's fill stage runs.
nlohmann::ordered_json BenchStereoFill(const std::vector<RgbdFrame>& frames,
                                       const Trajectory& tracked, const Camera& camera,
                                       const BenchOptions& options) {
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  KeyframeFiller filler(camera, options.pipeline.fill_options.Filler());
  std::vector<double> pair_ms, fill_ms, carry_ms, sgbm_ms;
  long long holes = 0, filled = 0, filled_with_carry = 0;
  int unpaired = 0, failed = 0;
  std::map<std::string, int> methods, paths;
  auto process = [&](const FilledKeyframe& k) {
    holes += k.record.hole_pixels;
    filled_with_carry += k.record.filled_pixels;
    carry_ms.push_back(k.carry_ms);
    failed += !k.record.failure.empty();
    if (!k.partner) {
      unpaired += k.record.failure.empty();
      return;
    }
    const StereoFillResult& r = k.stereo;
    fill_ms.push_back(k.stereo_ms);
    filled += r.filled_pixels;
    ++methods[r.method == FillMethod::kNone ? r.termination : FillMethodName(r.method)];
    ++paths[PairPathName(r.path)];
    if (r.rectification.usable) {
      const std::optional<double> ms =
          TimeOpenCvSgbm(k.key->frame, k.partner->frame, camera, r.rectification,
                         options.pipeline.fill_options.stereo.sgbm);
      if (ms) sgbm_ms.push_back(*ms);
    }
  };
  const int keyframes =
      (static_cast<int>(frames.size()) + options.fill_every - 1) / options.fill_every;
  const std::unique_ptr<Progress> progress = ShowProgress("bench: stereo fill", keyframes);
  for (int i = 0, k = 0; i < static_cast<int>(frames.size()); i += options.fill_every, ++k) {
    for (const FilledKeyframe& f : filler.Add(frames[i], tracked[i].world_from_camera)) process(f);
    pair_ms.push_back(filler.last_pairing_ms());
    progress->Update(k + 1);
  }
  for (const FilledKeyframe& f : filler.Flush()) process(f);
  cv::setNumThreads(threads);
  nlohmann::ordered_json j;
  j["keyframe_every"] = options.fill_every;
  j["threads"] = 1;
  j["keyframes"] = keyframes;
  j["pairs"] = fill_ms.size();
  j["unpaired_keyframes"] = unpaired;
  j["failed_keyframes"] = failed;
  j["pair_selection_median_ms"] = Median(pair_ms);  // features, matching, pose refinement
  j["median_ms"] = Median(fill_ms);                 // FillHolesByStereo
  j["max_ms"] = fill_ms.empty() ? 0.0 : *std::max_element(fill_ms.begin(), fill_ms.end());
  j["carry_median_ms"] = Median(carry_ms);  // CarryFills + FillPointsInWorld, every keyframe
  j["fill_rate"] = holes ? static_cast<double>(filled) / holes : 0.0;  // own stereo
  j["fill_rate_with_carry"] = holes ? static_cast<double>(filled_with_carry) / holes : 0.0;
  j["methods"] = methods;
  j["pair_paths"] = paths;
  j["opencv_sgbm_pairs"] = sgbm_ms.size();
  j["opencv_sgbm_median_ms"] =
      sgbm_ms.empty() ? nlohmann::json(nullptr) : nlohmann::json(Median(sgbm_ms));
  return j;
}

// Our tracker, frame to keyframe, one frame after the other (lost frames have no pose).
MethodResult TrackFrames(const std::vector<RgbdFrame>& frames, const Camera& camera,
                         const BenchOptions& options) {
  MethodResult ours{"glassfusion frame-to-keyframe ICP", {}, {}, 0};
  FrameToKeyframeTracker tracker(camera, options.pipeline.tracker);
  const std::unique_ptr<Progress> progress = ShowProgress("bench: glassfusion", static_cast<int>(frames.size()));
  for (const RgbdFrame& f : frames) {
    const auto t0 = Clock::now();
    const TrackingResult r = tracker.Track(f);
    ours.ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    ours.failures += !r.has_pose();
    if (r.has_pose()) ours.trajectory.push_back({f.timestamp, f.timestamp_text, r.world_from_camera});
    progress->Update(static_cast<int>(ours.ms.size()));
  }
  return ours;
}

// The same tracker refined against the surfel map of the frames before each one, fused as it
// goes (the pipeline's --frame-to-model, without threads); ms include the fusion.
MethodResult TrackFramesToModel(const std::vector<RgbdFrame>& frames, const Camera& camera,
                                const BenchOptions& options) {
  MethodResult model{"glassfusion frame-to-model ICP (+ fusion)", {}, {}, 0};
  FrameToKeyframeTracker tracker(camera, options.pipeline.tracker);
  SurfelFusion fusion(camera, options.pipeline.fusion_options.fusion);
  const std::unique_ptr<Progress> progress = ShowProgress("bench: glassfusion frame-to-model", static_cast<int>(frames.size()));
  SE3 last;
  for (size_t i = 0; i < frames.size(); ++i) {
    const auto t0 = Clock::now();
    if (i > 0) tracker.SetModelReference(fusion.RenderDepth(last), last);
    const TrackingResult r = tracker.Track(frames[i]);
    if (r.has_pose()) {
      fusion.FuseFrame(frames[i], r.world_from_camera, 0);
      last = r.world_from_camera;
      model.trajectory.push_back({frames[i].timestamp, frames[i].timestamp_text, last});
    }
    model.ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    model.failures += !r.has_pose();
    progress->Update(static_cast<int>(i + 1));
  }
  return model;
}

// The pipeline in-process (its stage threads) on the frames in memory, as reconstruct runs it
// with `pipeline` (the whole of it, or tracking with loop closure alone): the trajectory it
// writes, ms per frame of the whole run, and its report.json. With `to_disk` the outputs are
// written as reconstruct writes them (PNG, PLY, reports), into a temporary run folder removed
// afterwards; else kept in memory. *peak_added_mib: the most resident memory the run held above
// what the process held before it (sampled every 50 ms).
nlohmann::ordered_json BenchPipeline(const std::vector<RgbdFrame>& frames,
                                     const CameraFile& camera, ReconstructionOptions pipeline,
                                     const std::string& name, MethodResult* result,
                                     double* peak_added_mib, bool to_disk = false) {
  pipeline.first_frame = 0;
  pipeline.end_frame = -1;
  InMemoryFrameSource source(camera, frames);
  InMemoryRunSink in_memory;
  std::string folder;
  std::unique_ptr<FolderRunSink> on_disk;
  if (to_disk) {
    std::string pattern =
        (std::filesystem::temp_directory_path() / "glassfusion-bench-XXXXXX").string();
    GF_CHECK(mkdtemp(pattern.data()) != nullptr, "bench: cannot make a temporary folder");
    folder = pattern;
    on_disk = std::make_unique<FolderRunSink>(folder, RunFolder::Options{});
  }
  RunSink& sink = on_disk ? static_cast<RunSink&>(*on_disk) : in_memory;
  const std::unique_ptr<Progress> progress = ShowProgress("bench: " + name, static_cast<int>(frames.size()));
  const double before_mib = ResidentMiB();
  double peak_mib = before_mib;
  ReconstructionCallbacks callbacks;
  callbacks.progress = [&](const ReconstructionProgress& p) {
    peak_mib = std::max(peak_mib, ResidentMiB());
    progress->Update(p.frames);
  };
  const ReconstructionSummary s = Reconstruction(pipeline).Run(source, &sink, callbacks);
  if (peak_added_mib) *peak_added_mib = std::max(peak_mib, ResidentMiB()) - before_mib;
  result->name = name;
  if (on_disk) {
    on_disk.reset();
    result->trajectory = RunReader(folder).Poses();
    std::error_code ignored;
    std::filesystem::remove_all(folder, ignored);  // the folder this call made
  } else {
    result->trajectory = in_memory.trajectory;
  }
  result->ms.assign(frames.size(), 1000.0 * s.seconds / frames.size());
  result->failures = s.lost;
  return s.report;
}

// The tracking pipeline with loop closure (threads: reader, tracker, loop closure; no fill, no
// fusion): report.json's "loops" (the loop stage's cost per keyframe).
nlohmann::ordered_json BenchLoopClosure(const std::vector<RgbdFrame>& frames,
                                        const CameraFile& camera, const BenchOptions& options,
                                        MethodResult* result) {
  ReconstructionOptions pipeline = options.pipeline;
  pipeline.fill = pipeline.fusion = false;
  pipeline.loop_closure = true;
  const nlohmann::ordered_json report = BenchPipeline(
      frames, camera, pipeline, "glassfusion + loop closure (pipeline)", result, nullptr);
  nlohmann::ordered_json loops = report["loops"];
  loops.erase("loops");  // the list of loops: in a run's report.json, not here
  return loops;
}

// The whole reconstruction as `reconstruct` runs it by default (fill, fusion, loop closure, the
// map's completion of the keyframes; outputs written to a temporary folder): frames per second
// end to end, the CPU seconds of each stage and the cores used, and the memory the run added.
nlohmann::ordered_json BenchEndToEnd(const std::vector<RgbdFrame>& frames,
                                     const CameraFile& camera, const BenchOptions& options,
                                     MethodResult* result) {
  double peak_added_mib = 0;
  const nlohmann::ordered_json report =
      BenchPipeline(frames, camera, options.pipeline, "glassfusion end to end (reconstruct)",
                    result, &peak_added_mib, true);
  nlohmann::ordered_json out;
  out["fps"] = report["fps"];
  out["seconds"] = report["seconds"];
  out["keyframes"] = report["keyframes"];
  out["loops_accepted"] = report["loops"].value("accepted", 0);
  out["cpu_seconds"] = report["stages"]["cpu_seconds"];
  out["peak_added_mib"] = peak_added_mib;
  out["stages"] = report["stages"];
  out["stages"].erase("cpu_seconds");
  return out;
}

// OpenCV's RGB-D odometry, frame to frame, on the same frames.
std::vector<MethodResult> RunOdometryPeers(const std::vector<RgbdFrame>& frames,
                                           const Camera& camera) {
  std::vector<MethodResult> results;
  cv::Mat k;
  camera.CvK().convertTo(k, CV_32F);
  std::vector<std::pair<std::string, cv::Ptr<cv::rgbd::Odometry>>> peers = {
      {"opencv RgbdOdometry", cv::rgbd::RgbdOdometry::create(k)},
      {"opencv ICPOdometry", cv::rgbd::ICPOdometry::create(k)},
      {"opencv RgbdICPOdometry", cv::rgbd::RgbdICPOdometry::create(k)},
      {"opencv FastICPOdometry", cv::rgbd::FastICPOdometry::create(k)},
  };
  std::vector<cv::Mat> gray(frames.size()), masks(frames.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    cv::cvtColor(frames[i].color, gray[i], cv::COLOR_BGR2GRAY);
    masks[i] = frames[i].depth > 0;
  }
  for (auto& [name, odometry] : peers) {
    MethodResult m{name, {}, {}, 0};
    const std::unique_ptr<Progress> progress = ShowProgress("bench: " + name, static_cast<int>(frames.size()));
    SE3 world_from_current;
    m.trajectory.push_back({frames[0].timestamp, frames[0].timestamp_text, world_from_current});
    for (size_t i = 1; i < frames.size(); ++i) {
      cv::Mat rt;
      const auto t0 = Clock::now();
      bool ok = false;
      try {
        ok = odometry->compute(gray[i - 1], frames[i - 1].depth, masks[i - 1], gray[i],
                               frames[i].depth, masks[i], rt);
      } catch (const cv::Exception&) {
        ok = false;
      }
      m.ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      if (ok && !rt.empty()) {
        world_from_current = world_from_current * SE3::FromMatrix(ToEigen(rt)).Inverse();
      } else {
        ++m.failures;
      }
      m.trajectory.push_back({frames[i].timestamp, frames[i].timestamp_text, world_from_current});
      progress->Update(static_cast<int>(i + 1));
    }
    results.push_back(std::move(m));
  }
  return results;
}

}  // namespace

bool BenchOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.Require(!input.empty(), "INPUT: the capture to time")
      .Require(first_frame >= 0 && (end_frame < 0 || end_frame > first_frame),
               "--frames A:B needs 0 <= A < B")
      .In("--fill-every", fill_every, 0, kMaxCaptureFrames, kMoreFramesThanACapture)
      .Part("source", source)
      .Part("settings", pipeline);
  return c.ok();
}

nlohmann::ordered_json RunBench(const BenchOptions& options) {
  std::string problem;
  if (!options.Check(&problem)) throw InputError(options.input, "bad options: " + problem);
  FrameSourceOptions source_options = options.source;
  source_options.load_color = true;  // our SURF features and RgbdOdometry need intensity
  std::unique_ptr<FrameSource> source = OpenFrameSource(options.input, source_options);
  const Camera camera = source->camera();
  BenchOptions resolved = options;  // with the sensor's readout time (camera.json)
  resolved.pipeline.tracker = ForSensor(options.pipeline.tracker, source->camera_file());

  std::vector<RgbdFrame> frames;
  {
    const std::unique_ptr<Progress> progress = ShowProgress("bench: loading", source->FrameCount());
    RgbdFrame f;
    for (int index = 0; (options.end_frame < 0 || index < options.end_frame) && source->Next(&f);
         ++index) {
      if (index >= options.first_frame) frames.push_back(f);
      progress->Update(index + 1);
    }
  }
  if (frames.size() < 2) throw InputError(options.input, "bench needs at least 2 frames");

  const std::string gt_path = options.gt.empty() ? GroundTruthBeside(options.input) : options.gt;
  Trajectory gt;
  if (!gt_path.empty()) gt = ReadTrajectory(gt_path);

  std::vector<MethodResult> results;
  results.push_back(TrackFrames(frames, camera, resolved));
  nlohmann::ordered_json end_to_end;
  if (options.end_to_end) {
    MethodResult m;
    end_to_end = BenchEndToEnd(frames, source->camera_file(), resolved, &m);
    results.push_back(std::move(m));
  }
  nlohmann::ordered_json loop_closure;
  if (options.loop_closure) {
    MethodResult m;
    loop_closure = BenchLoopClosure(frames, source->camera_file(), resolved, &m);
    results.push_back(std::move(m));
  }
  if (options.frame_to_model) results.push_back(TrackFramesToModel(frames, camera, resolved));
  nlohmann::ordered_json stereo_fill;
  if (options.fill_every > 0)
    stereo_fill = BenchStereoFill(frames, results.front().trajectory, camera, options);
  nlohmann::ordered_json fusion;
  if (options.fusion)
    fusion = BenchFusion(frames, results.front().trajectory, camera,
                         options.pipeline.fusion_options.fusion);
  if (options.peers)
    for (MethodResult& m : RunOdometryPeers(frames, camera)) results.push_back(std::move(m));

  nlohmann::ordered_json out;
  out["input"] = options.input;
  out["frames"] = frames.size();
  out["cores"] = std::thread::hardware_concurrency();
  out["ground_truth"] = gt_path.empty() ? nlohmann::json(nullptr) : nlohmann::json(gt_path);
  out["methods"] = nlohmann::json::array();
  for (const MethodResult& m : results)
    out["methods"].push_back(Summarise(m, gt.empty() ? nullptr : &gt));
  if (!stereo_fill.is_null()) out["stereo_fill"] = stereo_fill;
  if (!fusion.is_null()) out["fusion"] = fusion;
  if (!loop_closure.is_null()) out["loop_closure"] = loop_closure;
  if (!end_to_end.is_null()) out["end_to_end"] = end_to_end;
  out["settings"] = SettingsToJson(resolved.pipeline);
  return out;
}

}  // namespace gf
