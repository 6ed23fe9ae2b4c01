// SURF on a 640x480 frame, one core: `build/registration/registration_surf_benchmark`.
// Uses a real TUM frame when ../shared/datasets is present, else a blurred noise image.
#include <benchmark/benchmark.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "registration/surf.h"

namespace {

cv::Mat Frame() {
  cv::Mat image =
      cv::imread(std::string(GF_SHARED_DATASETS) + "/tum_fr1_xyz_head/rgb/1305031102.175304.png",
                 cv::IMREAD_GRAYSCALE);
  if (image.empty()) {
    image.create(480, 640, CV_8UC1);
    cv::randu(image, 0, 255);
    cv::GaussianBlur(image, image, cv::Size(0, 0), 2.0);
  }
  return image;
}

void BM_Surf(benchmark::State& state) {
  const cv::Mat image = Frame();
  gf::SurfOptions options;
  options.upright = state.range(0) != 0;
  size_t keypoints = 0;
  for (auto _ : state) keypoints = gf::DetectAndDescribeSurf(image, options).keypoints.size();
  state.counters["keypoints"] = static_cast<double>(keypoints);
}
BENCHMARK(BM_Surf)->Arg(0)->Arg(1)->ArgName("upright")->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
