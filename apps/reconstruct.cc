#include "apps/reconstruct.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <thread>

#include "acquisition/camera.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/trajectory.h"
#include "apps/bounded_queue.h"
#include "apps/config.h"
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
  try {
    const std::string a = range.substr(0, colon), b = range.substr(colon + 1);
    *first = a.empty() ? 0 : std::stoi(a);
    *end = b.empty() ? -1 : std::stoi(b);
  } catch (const std::exception&) {
    throw InputError("--frames", "\"" + range + "\" is not A:B with frame numbers");
  }
  if (*first < 0 || (*end >= 0 && *end <= *first))
    throw InputError("--frames", "\"" + range + "\" needs 0 <= A < B");
}

ReconstructSummary RunReconstruct(const ReconstructOptions& options) {
  std::string problem;
  if (!options.Check(&problem)) throw InputError(options.out_dir, "bad options: " + problem);
  std::unique_ptr<FrameSource> source = OpenFrameSource(options.input, options.source);
  std::error_code ec;
  fs::create_directories(options.out_dir, ec);
  if (ec) throw InputError(options.out_dir, "cannot create output folder: " + ec.message());

  std::optional<int> total = source->FrameCount();
  if (total) {
    int last = options.end_frame >= 0 ? std::min(*total, options.end_frame) : *total;
    total = std::max(0, last - options.first_frame);
  }

  // Reader stage: decodes frames into the queue.
  BoundedQueue<Item> queue(options.queue_capacity);
  std::thread reader([&] {
    int index = 0;
    while (true) {
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

  FrameToKeyframeTracker tracker(source->camera(), options.tracker);
  std::unique_ptr<FillStage> fill;
  if (options.fill) {
    FillStageOptions fill_options = options.fill_options;
    fill_options.drop_when_busy = !total.has_value();  // live: never make tracking wait
    fill = std::make_unique<FillStage>(source->camera(), fill_options, options.out_dir);
  }
  Trajectory trajectory;
  std::vector<double> read_ms, track_ms;
  ReconstructSummary summary;
  TerminalProgress progress("reconstruct", total);
  const auto start = Clock::now();
  Item item;
  try {
    while (queue.Pop(&item)) {
      if (item.error) std::rethrow_exception(item.error);
      const auto t0 = Clock::now();
      const TrackingResult r = tracker.Track(item.frame);
      track_ms.push_back(Ms(t0, Clock::now()));
      read_ms.push_back(item.read_ms);
      if (r.status == TrackingStatus::kLost) {
        ++summary.lost;
        spdlog::debug("frame {} ({}): tracking lost: {}", item.frame.index,
                      item.frame.timestamp_text, r.BriefReport());
      }
      if (fill && r.new_keyframe && r.status != TrackingStatus::kLost) {
        if (item.frame.color.empty())
          throw InputError(item.frame.depth_path.empty() ? options.input : item.frame.depth_path,
                           "the stereo fill needs colour images (or --no-fill)");
        fill->Offer(item.frame, r.world_from_camera);
      }
      trajectory.push_back({item.frame.timestamp, item.frame.timestamp_text, r.world_from_camera});
      ++summary.frames;
      progress.Update(summary.frames);
    }
  } catch (...) {
    queue.Close();
    reader.join();
    throw;
  }
  reader.join();
  progress.Finish();
  summary.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (fill) {
    const auto t0 = Clock::now();
    fill->Finish();
    spdlog::info("stereo fill finished {:.1f} s after tracking", Ms(t0, Clock::now()) / 1000.0);
  }
  summary.fps = summary.seconds > 0 ? summary.frames / summary.seconds : 0;
  summary.keyframes = tracker.keyframes();
  if (trajectory.empty()) throw InputError(options.input, "no frames in the selected range");

  WriteTumTrajectory((fs::path(options.out_dir) / "trajectory.txt").string(), trajectory);
  // The camera of the run's images (frames arrive registered to colour; keyframe depth PNGs are
  // millimetres), for colmap-export and other readers of the run folder.
  CameraFile run_camera;
  run_camera.camera = source->camera();
  run_camera.depth_scale = 1000.0;
  SaveCameraFile((fs::path(options.out_dir) / "camera.json").string(), run_camera);
  nlohmann::ordered_json report;
  report["input"] = {{"path", options.input},
                     {"kind", source->Kind()},
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
  report["stages"] = {{"read", StageStats(read_ms)}, {"track", StageStats(track_ms)}};
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
  if (fill) {
    summary.hole_pixels = report["fill"]["hole_pixels"];
    summary.filled_pixels = report["fill"]["filled_pixels"];
  }
  report["surfels"] = nullptr;  // surfel fusion: not built yet
  WriteTextFileAtomically((fs::path(options.out_dir) / "report.json").string(),
                          report.dump(2) + "\n");
  return summary;
}

}  // namespace gf
