// The stereo fill of one keyframe pair on one core, on real frames:
// `build/fill/fill_stereo_fill_benchmark`. Keyframe 1 is frame K of tum_fr1_xyz_head (the argument),
// its candidates frames K + 9 and K + 18 (keyframes every third frame, three apart; the camera
// moves mostly forward there, so the plane sweep serves the pair). Poses as a run gets them:
// tracked, then refined by pair selection (SelectPartner, not timed), which also chooses the
// partner and the third view. Skipped (an error, no timing) when ../shared/datasets is absent.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <opencv2/core/utility.hpp>
#include <string>
#include <vector>

#include "acquisition/frame_source.h"
#include "registration/tracker.h"
#include "fill/keyframe_pairs.h"
#include "fill/stereo_fill.h"

namespace {

struct Capture {
  gf::Camera camera;
  std::vector<gf::RgbdFrame> frames;
  std::vector<gf::SE3> world_from_camera;  // as tracked
};

const Capture* LoadHead() {
  static std::unique_ptr<Capture> capture;
  if (capture) return capture.get();
  const std::string folder = std::string(GF_SHARED_DATASETS) + "/tum_fr1_xyz_head";
  if (!std::filesystem::exists(folder)) return nullptr;
  auto source = gf::OpenFrameSource(folder, gf::FrameSourceOptions{});
  capture = std::make_unique<Capture>();
  capture->camera = source->camera();
  gf::FrameToKeyframeTracker tracker(capture->camera, gf::TrackerOptions{});
  gf::RgbdFrame frame;
  while (source->Next(&frame)) {
    capture->world_from_camera.push_back(tracker.Track(frame).world_from_camera);
    capture->frames.push_back(frame);
    frame = gf::RgbdFrame();  // the next frame must not reuse (and overwrite) the kept images
  }
  return capture.get();
}

void BM_FillHolesByStereo(benchmark::State& state) {
  const Capture* capture = LoadHead();
  const size_t k1 = static_cast<size_t>(state.range(0));
  if (capture == nullptr || k1 + 18 >= capture->frames.size()) {
    state.SkipWithError("needs ../shared/datasets/tum_fr1_xyz_head");
    return;
  }
  const gf::PairSelectionOptions options;
  std::vector<std::shared_ptr<const gf::StereoKeyframe>> keys;
  for (size_t k : {k1, k1 + 9, k1 + 18})
    keys.push_back(gf::MakeStereoKeyframe(static_cast<int>(k), capture->frames[k],
                                          capture->world_from_camera[k], capture->camera,
                                          options.surf));
  const gf::PairChoice choice =
      gf::SelectPartner(*keys[0], {keys[1], keys[2]}, capture->camera, options);
  if (!choice.found) {
    state.SkipWithError(("no pair: " + choice.reason).c_str());
    return;
  }
  const gf::RgbdFrame& key2 = keys[1 + choice.partner]->frame;
  gf::ThirdView third;
  if (choice.third >= 0) third = {&keys[1 + choice.third]->frame, choice.third_pose.key1_from_key2};
  gf::StereoFillResult result;
  cv::setNumThreads(1);  // one core, OpenCV's calls included
  for (auto _ : state) {
    result =
        gf::FillHolesByStereo(keys[0]->frame, key2, capture->camera,
                              choice.partner_pose.key1_from_key2, gf::StereoFillOptions{}, third);
  }
  state.counters["filled_pixels"] = result.success ? cv::countNonZero(result.fill_mask) : 0;
  state.SetLabel(std::string(PairPathName(result.path)) + ": " + result.termination);
}
BENCHMARK(BM_FillHolesByStereo)
    ->Arg(0)
    ->Arg(60)
    ->Arg(120)
    ->ArgName("frame")
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
