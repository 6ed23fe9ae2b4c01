#include "eval/fill_truth.h"

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "acquisition/camera.h"
#include "acquisition/errors.h"
#include "acquisition/frame_source.h"
#include "acquisition/image_io.h"
#include "acquisition/run_layout.h"
#include "datasets/synth.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

// A 16-bit depth image as metres (value / scale), as CV_64F.
cv::Mat Metres(const cv::Mat& depth16, double scale) {
  cv::Mat out(depth16.size(), CV_64F);
  for (int v = 0; v < depth16.rows; ++v)
    for (int u = 0; u < depth16.cols; ++u)
      out.at<double>(v, u) = depth16.at<uint16_t>(v, u) / scale;
  return out;
}

void ScoreKeyframe(const std::string& scene_dir, const RunLayout& run, const std::string& ts,
                   double truth_scale, FillScore* score) {
  const cv::Mat filled = ReadDepthImage(run.Path(ts, KeyframeImage::kDepthFilled));
  const cv::Mat holes = cv::imread(run.Path(ts, KeyframeImage::kHoleMask), cv::IMREAD_UNCHANGED);
  const cv::Mat label =
      cv::imread((fs::path(scene_dir) / "gt/label" / (ts + ".png")).string(), cv::IMREAD_UNCHANGED);
  const cv::Mat truth =
      ReadDepthImage((fs::path(scene_dir) / "gt/visible_depth" / (ts + ".png")).string());
  const cv::Mat first_surface =
      ReadDepthImage((fs::path(scene_dir) / "gt/depth" / (ts + ".png")).string());
  // Absent with --no-glass, or when the map holds no glass in the keyframe's view.
  const std::string glass_file = run.Path(ts, KeyframeImage::kGlassMask);
  const cv::Mat glass = fs::exists(glass_file)
                            ? cv::imread(glass_file, cv::IMREAD_UNCHANGED)
                            : cv::Mat::zeros(label.size(), CV_8U);
  if (holes.empty() || label.empty() || glass.size() != label.size())
    throw InputError(run.Path(RunLayout::kKeyframes),
                     "keyframe " + ts + ": a mask or the label missing, or of another size");
  ScoreKeyframeFill(Metres(filled, 1000.0), holes, label, Metres(truth, truth_scale),
                    Metres(first_surface, truth_scale), glass, score);
}

}  // namespace

std::string MaterialName(int m) { return synth::MaterialName(static_cast<synth::Material>(m)); }

void ScoreKeyframeFill(const cv::Mat& filled_m, const cv::Mat& holes, const cv::Mat& label,
                       const cv::Mat& truth_m, const cv::Mat& first_surface_m,
                       const cv::Mat& glass, FillScore* score) {
  GF_CHECK(filled_m.type() == CV_64F && truth_m.type() == CV_64F && holes.type() == CV_8U &&
               label.type() == CV_8U && filled_m.size() == label.size() &&
               holes.size() == label.size() && truth_m.size() == label.size(),
           "ScoreKeyframeFill: CV_64F depths and CV_8U masks of one size");
  const bool glass_known = first_surface_m.size() == label.size() && glass.size() == label.size();
  const int clear_glass = static_cast<int>(synth::Material::kClearGlass);
  for (int v = 0; v < label.rows; ++v)
    for (int u = 0; u < label.cols; ++u) {
      const int m = label.at<uint8_t>(v, u);
      if (m >= kSynthMaterials || holes.at<uint8_t>(v, u) == 0) continue;
      ++score->holes[m];
      const double z = filled_m.at<double>(v, u), t = truth_m.at<double>(v, u);
      if (!(z > 0) || !(t > 0)) continue;
      ++score->filled[m];
      const double e = std::abs(z - t) / t;
      score->errors[m].push_back(static_cast<float>(e));
      score->good[m] += e <= 0.03;
      if (glass_known && m == clear_glass &&
          synth::AtClearGlassDepth(z, first_surface_m.at<double>(v, u), t))
        ++(glass.at<uint8_t>(v, u) ? score->clear_glass_marked_at_glass_depth
                                   : score->clear_glass_at_glass_depth);
    }
}

SensorHoles MeasureSensorHoles(const std::string& scene_dir, RgbdFrame* first) {
  auto source = OpenFrameSource(scene_dir, {});
  SensorHoles h;
  RgbdFrame frame;
  while (source->Next(&frame)) {
    const cv::Mat label =
        cv::imread((fs::path(scene_dir) / "gt/label" / (frame.timestamp_text + ".png")).string(),
                   cv::IMREAD_UNCHANGED);
    if (label.empty())
      throw InputError(scene_dir, "ground-truth label of " + frame.timestamp_text + " missing");
    for (int v = 0; v < label.rows; ++v)
      for (int u = 0; u < label.cols; ++u) {
        const int m = label.at<uint8_t>(v, u);
        if (m >= kSynthMaterials) continue;
        ++h.pixels[m];
        h.holes[m] += frame.hole_mask.at<uint8_t>(v, u) != 0;
      }
    if (frame.index == 0) *first = frame;
  }
  return h;
}

FillScore ScoreFill(const std::string& scene_dir, const std::string& run_dir) {
  const double truth_scale =
      LoadCameraFile((fs::path(scene_dir) / "camera.json").string()).depth_scale;
  FillScore score;
  const RunLayout run(run_dir);
  for (const auto& entry : fs::directory_iterator(run.Path(RunLayout::kKeyframes))) {
    const std::string name =
        RunLayout::KeyframeOf(entry.path().filename().string(), KeyframeImage::kDepthFilled);
    if (!name.empty()) ScoreKeyframe(scene_dir, run, name, truth_scale, &score);
  }
  return score;
}

}  // namespace gf
