#include "runs/bench_fusion.h"

#include <algorithm>
#include <opencv2/core/utility.hpp>

#include "acquisition/progress.h"
#include "pipeline/stage_reports.h"

namespace gf {
namespace {

using json = nlohmann::ordered_json;

// Fuses every frame into `fusion` with `threads` threads; the milliseconds of each.
std::vector<double> FuseAll(const std::vector<RgbdFrame>& frames, const Trajectory& tracked,
                            int threads, SurfelFusion* fusion, Progress* progress) {
  cv::setNumThreads(threads);
  std::vector<double> ms;
  for (size_t i = 0; i < frames.size(); ++i) {
    ms.push_back(fusion->FuseFrame(frames[i], tracked[i].world_from_camera, 0).ms);
    progress->Update(static_cast<int>(i + 1));
  }
  return ms;
}

}  // namespace

json BenchFusion(const std::vector<RgbdFrame>& frames, const Trajectory& tracked,
                 const Camera& camera, const FusionOptions& options, size_t large_map_surfels) {
  const int threads = cv::getNumThreads();
  json out;
  out["frames"] = frames.size();
  out["bytes_per_surfel"] = sizeof(Surfel);
  std::vector<Surfel> built;
  for (int t : {1, 2}) {
    SurfelFusion fusion(camera, options);
    const std::unique_ptr<Progress> progress = ShowProgress(
        "bench: fusion, " + std::to_string(t) + " thread(s)", static_cast<int>(frames.size()));
    out["map"]["threads_" + std::to_string(t)] =
        StepTimes::Of(FuseAll(frames, tracked, t, &fusion, progress.get()));
    out["map"]["surfels"] = fusion.map().live();
    out["map"]["stable_surfels"] = fusion.Counts().total_stable();
    out["map"]["memory_bytes"] = fusion.MemoryBytes();
    built = fusion.map().ToVector();
  }
  // The same frames into a map that already holds about large_map_surfels: copies of the map
  // built above, each moved 50 m further along x (out of every frame's view).
  if (!built.empty()) {
    std::vector<Surfel> copies;
    for (int k = 1; copies.size() + built.size() < large_map_surfels; ++k)
      for (Surfel s : built) {
        s.position.x() += 50.f * k;
        copies.push_back(s);
      }
    for (int t : {1, 2}) {
      SurfelFusion fusion(camera, options);
      fusion.AddSurfels(copies);
      const std::unique_ptr<Progress> progress = ShowProgress("bench: fusion, large map, " + std::to_string(t) + " thread(s)",
                                static_cast<int>(frames.size()));
      const std::vector<double> ms = FuseAll(frames, tracked, t, &fusion, progress.get());
      out["large_map"]["threads_" + std::to_string(t)] = StepTimes::Of(ms);
      out["large_map"]["surfels"] = fusion.map().live();
      out["large_map"]["memory_bytes"] = fusion.MemoryBytes();
    }
  }
  cv::setNumThreads(threads);
  return out;
}

}  // namespace gf
