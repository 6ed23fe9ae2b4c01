#include "apps/reconstruct.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <thread>

#include "acquisition/camera.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/stats.h"
#include "acquisition/trajectory.h"
#include "apps/bounded_queue.h"
#include "apps/config.h"
#include "apps/interrupt.h"
#include "apps/progress.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

using Clock = std::chrono::steady_clock;

double Ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

nlohmann::ordered_json StageStats(std::vector<double> ms) {
  if (ms.empty()) return {{"median_ms", nullptr}, {"max_ms", nullptr}, {"count", 0}};
  std::sort(ms.begin(), ms.end());
  return {{"median_ms", ms[ms.size() / 2]}, {"max_ms", ms.back()}, {"count", ms.size()}};
}

// A frame that failed to read travels down the queue as an error, so it reaches the main thread.
struct Item {
  RgbdFrame frame;
  double read_ms = 0;
  std::exception_ptr error;
};

// Frames whose depth decides whether the depth scale is plausible (DepthScaleProblem).
constexpr int kDepthScaleFrames = 10;
// A run that loses tracking on more than this share of its frames has no usable trajectory.
constexpr double kMostFramesLost = 0.5;

// Everything a run has done so far, so that it can be reported however the run ends.
struct RunRecord {
  Trajectory trajectory;
  std::vector<double> read_ms, track_ms;
  ReconstructSummary summary;
  std::vector<double> median_depths;  // of the first frames with returns, metres
  Clock::time_point start = Clock::now();
};

bool LooksLikeRun(const fs::path& dir) {
  for (const char* name : {"report.json", "trajectory.txt", "keyframes", "camera.json"})
    if (fs::exists(dir / name)) return true;
  return false;
}

// out_dir must be new or empty; with `force`, an earlier run in it is removed first (a folder
// that does not look like a run is never emptied).
void PrepareOutputFolder(const std::string& out_dir, bool force) {
  std::error_code ec;
  const fs::path dir(out_dir);
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw InputError(out_dir, "exists and is not a folder");
  if (fs::is_directory(dir, ec) && !fs::is_empty(dir, ec)) {
    if (!force)
      throw InputError(out_dir,
                       "is not empty (an earlier run?); choose a new folder, or --force to "
                       "replace the run in it");
    if (!LooksLikeRun(dir))
      throw InputError(out_dir,
                       "is not empty and holds no run (no report.json, trajectory.txt or "
                       "keyframes/); --force replaces only runs");
    for (const auto& entry : fs::directory_iterator(dir, ec)) fs::remove_all(entry.path(), ec);
    if (ec) throw InputError(out_dir, "cannot remove the earlier run: " + ec.message());
  }
  fs::create_directories(dir, ec);
  if (ec) throw InputError(out_dir, "cannot create output folder: " + ec.message());
}

std::string CameraFilePath(const ReconstructOptions& options) {
  if (!options.source.camera_file.empty()) return options.source.camera_file;
  return fs::is_directory(options.input) ? (fs::path(options.input) / "camera.json").string()
                                         : options.input;
}

// Checks the first frames' depth against an indoor capture's (the depth scale).
void CheckDepthScale(const ReconstructOptions& options, const FrameSource& source,
                     const RgbdFrame& frame, RunRecord* run) {
  if (frame.median_return_m <= 0 || run->median_depths.size() >= kDepthScaleFrames) return;
  run->median_depths.push_back(frame.median_return_m);
  if (run->median_depths.size() < kDepthScaleFrames) return;
  const std::string problem =
      DepthScaleProblem(Median(run->median_depths), source.depth_convention());
  if (!problem.empty()) throw InputError(CameraFilePath(options), problem);
}

void WriteOutputs(const ReconstructOptions& options, const FrameSource& source,
                  const RunRecord& run, const FillStage* fill, const std::string& stopped_because) {
  const fs::path out(options.out_dir);
  WriteTumTrajectory((out / "trajectory.txt").string(), run.trajectory);
  // The camera of the run's images (frames arrive registered to colour; keyframe depth PNGs are
  // millimetres), for colmap-export and other readers of the run folder.
  CameraFile run_camera;
  run_camera.camera = source.camera();
  run_camera.depth_scale = 1000.0;
  SaveCameraFile((out / "camera.json").string(), run_camera);
  const ReconstructSummary& summary = run.summary;
  nlohmann::ordered_json report;
  report["complete"] = stopped_because.empty();
  if (!stopped_because.empty()) report["stopped_because"] = stopped_because;
  report["input"] = {{"path", options.input},
                     {"kind", source.Kind()},
                     {"first_frame", options.first_frame},
                     {"end_frame", options.end_frame}};
  report["config"] = {
      {"tracker", "frame_to_keyframe_icp"},
      {"stereo_fill", options.fill},
      {"threads", options.fill ? "reader + tracker + stereo" : "reader + tracker"},
      {"hardware_concurrency", std::thread::hardware_concurrency()},
      {"file", options.config_file.empty() ? nlohmann::ordered_json()
                                           : nlohmann::ordered_json(options.config_file)},
      {"settings", SettingsToJson(options.tracker, options.fill_options)}};
  report["frames"] = summary.frames;
  report["fps"] = summary.fps;
  report["stages"] = {{"read", StageStats(run.read_ms)}, {"track", StageStats(run.track_ms)}};
  if (fill) {
    std::vector<double> stereo_ms;  // per keyframe: pairing, pose refinement, stereo, validation
    for (const KeyframeFill& k : fill->keyframes())
      if (!k.partner.empty()) stereo_ms.push_back(k.ms);
    report["stages"]["stereo"] = StageStats(stereo_ms);
  }
  report["keyframes"] = summary.keyframes;
  report["tracking"] = {{"lost_frames", summary.lost}};
  report["loops"] = nullptr;  // loop closure: not built yet
  report["fill"] = fill ? fill->Report() : nlohmann::ordered_json();
  report["surfels"] = nullptr;  // surfel fusion: not built yet
  report["warnings"] = summary.warnings;
  WriteTextFileAtomically((out / "report.json").string(), report.dump(2) + "\n");
}

// Tracks every frame the reader delivers (and hands keyframes to the fill). Returns normally at
// the end of the input or when interrupted; throws what the reader or the fill threw.
void TrackFrames(const ReconstructOptions& options, const FrameSource& source,
                 BoundedQueue<Item>* queue, FillStage* fill, std::optional<int> total,
                 RunRecord* run) {
  FrameToKeyframeTracker tracker(source.camera(), options.tracker);
  ReconstructSummary& summary = run->summary;
  TerminalProgress progress("reconstruct", total);
  Item item;
  while (queue->Pop(&item)) {
    if (item.error) std::rethrow_exception(item.error);
    if (options.interrupt && *options.interrupt) break;
    CheckDepthScale(options, source, item.frame, run);
    const auto t0 = Clock::now();
    const TrackingResult r = tracker.Track(item.frame);
    run->track_ms.push_back(Ms(t0, Clock::now()));
    run->read_ms.push_back(item.read_ms);
    if (r.status == TrackingStatus::kLost) {
      ++summary.lost;
      spdlog::debug("frame {} ({}): tracking lost: {}", item.frame.index, item.frame.timestamp_text,
                    r.BriefReport());
    }
    if (fill && r.new_keyframe && r.status != TrackingStatus::kLost) {
      if (item.frame.color.empty())
        throw InputError(item.frame.depth_path.empty() ? options.input : item.frame.depth_path,
                         "the stereo fill needs colour images (or --no-fill)");
      fill->Offer(item.frame, r.world_from_camera);
    }
    run->trajectory.push_back(
        {item.frame.timestamp, item.frame.timestamp_text, r.world_from_camera});
    ++summary.frames;
    summary.keyframes = tracker.keyframes();
    progress.Update(summary.frames);
  }
  progress.Finish();
}

}  // namespace

bool ReconstructOptions::Check(std::string* message) const {
  if (input.empty() || out_dir.empty()) {
    if (message) *message = "need INPUT and --out";
    return false;
  }
  if (first_frame < 0 || (end_frame >= 0 && end_frame <= first_frame) || queue_capacity < 1) {
    if (message) *message = "need 0 <= A < B in --frames A:B";
    return false;
  }
  return source.Check(message) && tracker.Check(message) && (!fill || fill_options.Check(message));
}

std::string ReconstructSummary::BriefReport() const {
  char buffer[200];
  std::snprintf(buffer, sizeof(buffer),
                "%d frames in %.1f s (%.1f fps), %d keyframes, %d lost, %ld of %ld keyframe hole "
                "pixels filled",
                frames, seconds, fps, keyframes, lost, filled_pixels, hole_pixels);
  return buffer;
}

void ParseFrameRange(const std::string& range, int* first, int* end) {
  const size_t colon = range.find(':');
  if (colon == std::string::npos) throw InputError("--frames", "expected A:B, A: or :B");
  // Whole numbers only: "1e3" must not silently read as 1.
  auto number = [&](const std::string& text, int if_empty) {
    if (text.empty()) return if_empty;
    int value = 0;
    const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || ptr != text.data() + text.size() || value < 0)
      throw InputError("--frames", "\"" + range + "\" is not A:B with whole frame numbers");
    return value;
  };
  *first = number(range.substr(0, colon), 0);
  *end = number(range.substr(colon + 1), -1);
  if (*end >= 0 && *end <= *first)
    throw InputError("--frames", "\"" + range + "\" needs 0 <= A < B");
}

ReconstructSummary RunReconstruct(const ReconstructOptions& options) {
  std::string problem;
  if (!options.Check(&problem)) throw InputError(options.out_dir, "bad options: " + problem);
  std::unique_ptr<FrameSource> source = OpenFrameSource(options.input, options.source);
  PrepareOutputFolder(options.out_dir, options.force);

  std::optional<int> total = source->FrameCount();
  if (total) {
    int last = options.end_frame >= 0 ? std::min(*total, options.end_frame) : *total;
    total = std::max(0, last - options.first_frame);
  }
  auto interrupted = [&] { return options.interrupt && *options.interrupt; };
  // Reader stage: decodes frames into the queue.
  BoundedQueue<Item> queue(options.queue_capacity);
  std::thread reader([&] {
    int index = 0;
    while (!interrupted()) {
      Item item;
      const auto t0 = Clock::now();
      try {
        if (options.end_frame >= 0 && index >= options.end_frame) break;
        if (!source->Next(&item.frame)) break;
      } catch (...) {
        item.error = std::current_exception();
        queue.Push(std::move(item));
        break;
      }
      item.read_ms = Ms(t0, Clock::now());
      if (index++ < options.first_frame) continue;
      if (!queue.Push(std::move(item))) break;
    }
    queue.Close();
  });

  std::unique_ptr<FillStage> fill;
  RunRecord run;
  std::exception_ptr error;  // what stopped the run, rethrown once its outputs are written
  try {
    if (options.fill) {
      FillStageOptions fill_options = options.fill_options;
      fill_options.drop_when_busy = !total.has_value();  // live: never make tracking wait
      fill = std::make_unique<FillStage>(source->camera(), fill_options, options.out_dir);
    }
    TrackFrames(options, *source, &queue, fill.get(), total, &run);
    run.summary.seconds = std::chrono::duration<double>(Clock::now() - run.start).count();
    if (fill) {
      const auto t0 = Clock::now();
      fill->Finish(interrupted);
      spdlog::info("stereo fill finished {:.1f} s after tracking", Ms(t0, Clock::now()) / 1000.0);
    }
  } catch (...) {
    error = std::current_exception();
  }
  queue.Close();
  reader.join();
  std::string stopped_because;
  if (error) {
    try {
      std::rethrow_exception(error);
    } catch (const std::exception& e) {
      stopped_because = e.what();
    }
    if (fill) {
      // The keyframes tracked before the error are valid: the fill finishes them (Ctrl-C stops
      // it), unless it is the fill that failed.
      try {
        fill->Finish(interrupted);
      } catch (const std::exception& e) {
        spdlog::warn("fill stage: {}", e.what());
      }
    }
  } else if (interrupted()) {
    stopped_because = "interrupted by " + SignalName(*options.interrupt);
  } else if (run.summary.frames == 0) {
    stopped_because = options.input + ": no frames in the selected range";
    error = std::make_exception_ptr(InputError(options.input, "no frames in the selected range"));
  }
  ReconstructSummary& summary = run.summary;
  if (summary.seconds == 0)
    summary.seconds = std::chrono::duration<double>(Clock::now() - run.start).count();
  summary.fps = summary.seconds > 0 ? summary.frames / summary.seconds : 0;
  if (fill) {
    const nlohmann::ordered_json f = fill->Report();
    summary.hole_pixels = f["hole_pixels"];
    summary.filled_pixels = f["filled_pixels"];
    for (const auto& k : f["failed_keyframes"])
      summary.warnings.push_back("keyframe " + k["timestamp"].get<std::string>() +
                                 " not filled: " + k["reason"].get<std::string>());
  }
  const bool most_lost = summary.frames >= 2 && summary.lost > kMostFramesLost * summary.frames;
  if (most_lost)
    summary.warnings.push_back("tracking was lost on " + std::to_string(summary.lost) + " of " +
                               std::to_string(summary.frames) + " frames");
  WriteOutputs(options, *source, run, fill.get(), stopped_because);
  if (error) std::rethrow_exception(error);
  if (!stopped_because.empty())
    throw Interrupted(*options.interrupt, options.out_dir + ": " + stopped_because + " after " +
                                              std::to_string(summary.frames) +
                                              " frames; partial run written (\"complete\": false)");
  if (most_lost && !options.allow_lost)
    throw InputError(options.input, summary.warnings.back() +
                                        ": the trajectory is not usable (is the depth valid? "
                                        "`glassfusion info` shows its holes); --allow-lost "
                                        "accepts such a run");
  return summary;
}

}  // namespace gf
