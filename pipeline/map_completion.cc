#include "pipeline/map_completion.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <map>
#include <memory>
#include <thread>

namespace gf {
namespace {

using Clock = std::chrono::steady_clock;

// One keyframe's completion from the map (CompleteFromMap).
struct KeyframeCompletion {
  bool done = false;      // asked for (a stop leaves the rest undone)
  int completed = 0;      // pixels
  int glass = 0;          // pixels the map's transparent surfels cover
  std::string warning;    // why it could not be completed
};

KeyframeCompletion CompleteOne(const KeyframeFill& k, const std::map<std::string, SE3>& poses,
                               FusionStage* fusion, RunSink* sink) {
  KeyframeCompletion out;
  out.done = true;
  const auto pose = poses.find(k.timestamp);
  if (!k.failure.empty() || pose == poses.end()) return out;
  try {
    const MapCompletion offer = fusion->RenderFills(pose->second);
    out.glass = offer.glass.empty() ? 0 : cv::countNonZero(offer.glass);
    out.completed = sink->CompleteKeyframe(k.timestamp, offer);
  } catch (const std::exception& e) {
    out.warning = "keyframe " + k.timestamp + " not completed from the model: " + e.what();
  }
  return out;
}

// Frame name -> pose, trajectory entry i being frame names[i].
std::map<std::string, SE3> PosesByName(const Trajectory& trajectory,
                                       const std::vector<std::string>& names) {
  std::map<std::string, SE3> poses;
  for (size_t i = 0; i < trajectory.size() && i < names.size(); ++i)
    poses[names[i]] = trajectory[i].world_from_camera;
  return poses;
}

}  // namespace

OutlineViews KeyframeViews(const FillStage& fill, const Trajectory& trajectory,
                           const std::vector<std::string>& names, const RunSink& sink, int count) {
  const std::map<std::string, SE3> poses = PosesByName(trajectory, names);
  std::vector<std::pair<std::string, SE3>> written;
  for (const KeyframeFill& k : fill.keyframes()) {
    const auto pose = poses.find(k.timestamp);
    if (k.failure.empty() && pose != poses.end()) written.emplace_back(k.timestamp, pose->second);
  }
  auto chosen = std::make_shared<std::vector<std::pair<std::string, SE3>>>();
  const size_t n = std::min(written.size(), static_cast<size_t>(std::max(0, count)));
  for (size_t i = 0; i < n; ++i) chosen->push_back(written[i * written.size() / n]);
  return [chosen, &sink](size_t index, OutlineView* view) {
    if (index >= chosen->size()) return false;
    view->image = sink.KeyframeColor((*chosen)[index].first);
    view->world_from_camera = (*chosen)[index].second;
    return true;
  };
}

ModelCompletionReport CompleteFromMap(const FillStage& fill, FusionStage* fusion,
                                      const Trajectory& trajectory,
                                      const std::vector<std::string>& names, RunSink* sink,
                                      const std::function<bool()>& stop,
                                      std::vector<std::string>* warnings) {
  const std::map<std::string, SE3> poses = PosesByName(trajectory, names);
  const auto start = Clock::now();
  const std::vector<KeyframeFill> keyframes_filled = fill.keyframes();
  std::vector<std::string> to_complete;
  for (const KeyframeFill& k : keyframes_filled)
    if (k.failure.empty() && poses.count(k.timestamp)) to_complete.push_back(k.timestamp);
  sink->PrepareCompletion(to_complete);
  fusion->PrepareRenders();
  std::vector<KeyframeCompletion> results(keyframes_filled.size());
  std::atomic<size_t> next{0};
  std::atomic<bool> stopped{false};
  auto work = [&](bool asks) {
    for (;;) {
      if (asks && stop()) stopped = true;
      if (stopped) return;
      const size_t i = next++;
      if (i >= results.size()) return;
      results[i] = CompleteOne(keyframes_filled[i], poses, fusion, sink);
    }
  };
  const size_t helpers =
      std::min<size_t>({std::max(1u, std::thread::hardware_concurrency()) - 1, 7,
                        results.size()});
  std::vector<std::thread> threads;
  for (size_t t = 0; t < helpers; ++t) threads.emplace_back(work, false);
  work(true);
  for (std::thread& t : threads) t.join();
  ModelCompletionReport report;
  for (const KeyframeCompletion& r : results) {
    report.keyframes_done += r.done;
    report.keyframes += r.completed > 0;
    report.pixels += r.completed;
    report.glass_keyframes += r.glass > 0;
    report.glass_pixels += r.glass;
    if (r.warning.empty()) continue;
    warnings->push_back(r.warning);
    spdlog::warn("{}", r.warning);
  }
  report.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  report.stopped = stopped.load();
  report.keyframes_to_do = static_cast<int>(keyframes_filled.size());
  spdlog::info("model completion: {} hole pixels of {} keyframes from the map's fills, {:.1f} s",
               report.pixels, report.keyframes, report.seconds);
  return report;
}

}  // namespace gf
