// Surfel fusion of 640x480 frames: `build/surfels/surfels_fusion_benchmark`.
// Real TUM frames (tum_fr1_xyz_head, at their ground-truth poses) when ../shared/datasets is
// present. Args: threads (cv::setNumThreads) and extra surfels already in the map before the
// frames, out of view (copies of the frames' stable surfels moved 50 m along x), as a long capture
// that has built them and scans on elsewhere holds them, so the cost of a large map shows. For
// instruction counts that do not depend on the machine's load:
//   valgrind --tool=callgrind build/surfels/surfels_fusion_benchmark --benchmark_min_time=0.05
#include <benchmark/benchmark.h>

#include <memory>
#include <opencv2/core/utility.hpp>

#include "acquisition/frame_source.h"
#include "acquisition/trajectory.h"
#include "surfels/fusion.h"

namespace {

constexpr int kFrames = 150;  // read from the capture: all of tum_fr1_xyz_head

struct Capture {
  std::vector<gf::RgbdFrame> frames;
  std::vector<gf::SE3> poses;
  gf::Camera camera;
};

// The first kFrames frames with the ground-truth pose nearest each (empty when absent).
const Capture& LoadCapture() {
  static const Capture capture = [] {
    Capture c;
    const std::string folder = std::string(GF_SHARED_DATASETS) + "/tum_fr1_xyz_head";
    try {
      auto source = gf::OpenFrameSource(folder, {});
      const gf::Trajectory truth = gf::ReadTrajectory(folder + "/groundtruth.txt");
      c.camera = source->camera();
      gf::RgbdFrame frame;
      while (static_cast<int>(c.frames.size()) < kFrames && source->Next(&frame)) {
        const gf::StampedPose* nearest = &truth.front();
        for (const gf::StampedPose& p : truth)
          if (std::abs(p.timestamp - frame.timestamp) <
              std::abs(nearest->timestamp - frame.timestamp))
            nearest = &p;
        c.poses.push_back(nearest->world_from_camera);
        c.frames.push_back(frame);
      }
    } catch (const std::exception&) {
      c.frames.clear();
    }
    return c;
  }();
  return capture;
}

void BM_FuseFrame(benchmark::State& state) {
  const Capture& c = LoadCapture();
  if (c.frames.empty()) {
    state.SkipWithError("tum_fr1_xyz_head not found under GF_SHARED_DATASETS");
    return;
  }
  const int threads = cv::getNumThreads();
  cv::setNumThreads(static_cast<int>(state.range(0)));
  std::vector<gf::Surfel> copies;
  if (state.range(1) > 0) {
    // A map that a long capture built before these frames: copies of their stable surfels (a
    // first fusion of all the frames), out of view, added first as they would have been.
    gf::SurfelFusion earlier(c.camera, {});
    for (size_t i = 0; i < c.frames.size(); ++i) earlier.FuseFrame(c.frames[i], c.poses[i], 0);
    const std::vector<gf::Surfel> built = earlier.StableSurfels();  // unstable ones would go
    for (int k = 1; copies.size() < static_cast<size_t>(state.range(1)); ++k)
      for (gf::Surfel s : built) {
        s.position.x() += 50.f * k;
        copies.push_back(s);
      }
  }
  // Every frame in turn, from an empty map (plus the copies), as a capture's run fuses them; the
  // map starts again after the last frame, out of the timing.
  std::unique_ptr<gf::SurfelFusion> fusion;
  size_t i = c.frames.size();
  size_t surfels = 0;
  for (auto _ : state) {
    if (i == c.frames.size()) {
      state.PauseTiming();
      fusion = std::make_unique<gf::SurfelFusion>(c.camera, gf::FusionOptions{});
      fusion->AddSurfels(copies);
      i = 0;
      state.ResumeTiming();
    }
    fusion->FuseFrame(c.frames[i], c.poses[i], 0);
    surfels = std::max(surfels, fusion->map().live());
    ++i;
  }
  state.counters["surfels"] = static_cast<double>(surfels);
  cv::setNumThreads(threads);
}
BENCHMARK(BM_FuseFrame)
    ->ArgsProduct({{1, 2}, {0, 1000000}})
    ->ArgNames({"threads", "extra_surfels"})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
