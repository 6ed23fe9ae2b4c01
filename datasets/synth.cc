#include "datasets/synth.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "acquisition/bounds.h"
#include "acquisition/depth.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/frame_sink.h"
#include "acquisition/image_io.h"
#include "acquisition/json_text.h"
#include "acquisition/names.h"
#include "acquisition/trajectory.h"

namespace fs = std::filesystem;

namespace gf::synth {
namespace {

std::string TimeText(double t) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.6f", t);
  return buffer;
}

// Writes a 16-bit P5 PGM with little-endian samples, as libfreenect's fakenect record does.
void WriteRawPgm(const std::string& path, const cv::Mat& raw) {
  WriteFileAtomically(path, [&](const std::string& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    out << "P5 " << raw.cols << " " << raw.rows << " 65535\n";
    for (int y = 0; y < raw.rows; ++y) {
      const uint16_t* r = raw.ptr<uint16_t>(y);
      for (int x = 0; x < raw.cols; ++x)
        out.put(static_cast<char>(r[x] & 0xFF)).put(static_cast<char>(r[x] >> 8));
    }
    if (!out) throw InputError(path, "write error");
  });
}

cv::Mat MetresToPng(const cv::Mat& metres) {
  return DepthToRaw(metres, DepthConvention::ScaledUnits(5000.0));
}

}  // namespace

namespace {
constexpr std::pair<const char*, Motion> kMotions[] = {{"orbit", Motion::kOrbit},
                                                       {"vertical", Motion::kVertical},
                                                       {"diagonal", Motion::kDiagonal},
                                                       {"forward", Motion::kForward}};
}  // namespace

bool ParseMotion(const std::string& text, Motion* motion) {
  return ValueOfName(kMotions, text, motion);
}

const char* MotionName(Motion motion) { return NameOfValue(kMotions, motion); }

bool SynthOptions::Check(std::string* message) const {
  const auto names = Scene::Names();
  if (std::find(names.begin(), names.end(), scene) == names.end()) {
    if (message)
      *message = "unknown scene \"" + scene + "\" (known: glass-table, shelf, window, bottles)";
    return false;
  }
  // A rendered capture is held in memory: at most 100,000 frames.
  FieldCheck c(message);
  c.In("frames", frames, 1, 100000, "is more frames than a rendered capture holds")
      .Above("fps", fps, 0, 10000, "is faster than any camera")
      .In("degrees_per_frame", degrees_per_frame, 0, kMaxAngleDeg, kMoreThanAHalfTurn)
      .In("jitter_m", jitter_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Part("kinect", kinect);
  return c.ok();
}

Camera SynthCamera() { return Camera{}; }  // 640x480, fx = fy = 525, cx 319.5, cy 239.5

CameraFile SynthCameraFile() {
  CameraFile file;
  file.camera = SynthCamera();
  file.depth_scale = 5000.0;
  file.depth_readout_s = 0.0;
  return file;
}

std::vector<SE3> MakeTrajectory(const Scene& scene, const SynthOptions& options) {
  std::vector<SE3> poses;
  const int n = options.frames;
  // Smooth handheld wobble: a few sines per axis with seeded phases. When looping, whole cycles
  // over the sequence, so the last frame runs back into the first.
  auto wobble = [&](int axis, double i, double amplitude) {
    double sum = 0;
    for (int k = 1; k <= 3; ++k) {
      const double phase = 2 * M_PI * HashUniform(axis, k, 0, options.seed ^ 0x5EEDu);
      const double cycles_per_frame =
          options.loop ? static_cast<double>(k) / n
                       : 0.01 + 0.03 * HashUniform(axis, k, 1, options.seed ^ 0x5EEDu);
      sum += std::sin(2 * M_PI * cycles_per_frame * i + phase) / k;
    }
    return amplitude * sum / 1.83;  // 1 + 1/2 + 1/3
  };
  // Distance travelled from the middle of the sequence, metres (a sine when looping).
  const double step_m = scene.orbit_radius() * options.degrees_per_frame * M_PI / 180.0;
  auto travel = [&](int i) {
    return options.loop ? step_m * n / (2 * M_PI) * std::sin(2 * M_PI * i / n)
                        : (i - (n - 1) / 2.0) * step_m;
  };
  const bool orbit = options.motion == Motion::kOrbit,
             diagonal = options.motion == Motion::kDiagonal;
  for (int i = 0; i < n; ++i) {
    double angle = scene.orbit_center_angle(), height = scene.eye_height();
    const double radius = scene.orbit_radius();
    if (orbit && options.loop) {
      angle += 2 * M_PI * i / n;
    } else if (orbit || diagonal) {
      angle += travel(i) / (diagonal ? std::sqrt(2.0) : 1.0) / radius;
    }
    if (options.motion == Motion::kVertical) height += travel(i);
    if (diagonal) height += travel(i) / std::sqrt(2.0);
    Eigen::Vector3d offset(radius * std::cos(angle), radius * std::sin(angle),
                           height - scene.focus().z());
    if (options.motion == Motion::kForward)  // along the line of sight, never nearer than 0.6 m
      offset *= std::max(0.6 / offset.norm(), 1.0 - travel(i) / offset.norm());
    const Eigen::Vector3d eye =
        scene.focus() + offset +
        Eigen::Vector3d(wobble(0, i, options.jitter_m), wobble(1, i, options.jitter_m),
                        wobble(2, i, options.jitter_m));
    const Eigen::Vector3d target =
        scene.focus() + Eigen::Vector3d(wobble(3, i, 2 * options.jitter_m),
                                        wobble(4, i, 2 * options.jitter_m),
                                        wobble(5, i, options.jitter_m));
    const Eigen::Vector3d forward = (target - eye).normalized();
    const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d down = forward.cross(right);
    Eigen::Matrix3d r;
    r.col(0) = right;
    r.col(1) = down;
    r.col(2) = forward;
    poses.emplace_back(r, eye);
  }
  return poses;
}

RgbdFrame ToRgbdFrame(const SynthFrame& f, int index) {
  RgbdFrame frame;
  frame.index = index;
  frame.color = f.color;
  ConvertDepth(f.raw_disparity, DepthConvention::KinectV1Raw11Bit(), {}, &frame.depth,
               &frame.hole_mask);
  frame.median_return_m = MedianReturnDepth(f.raw_disparity, DepthConvention::KinectV1Raw11Bit());
  ClassifyShadows(frame.depth, SynthCamera().fx, ShadowOptions{}, &frame.hole_mask);
  return frame;
}

std::string SynthSummary::BriefReport() const {
  char buffer[256];
  std::snprintf(buffer, sizeof(buffer), "%d frames, %.1f ms/frame, sensor hole fraction %.3f",
                frames, 1000.0 * seconds_per_frame, hole_fraction);
  std::string text = buffer;
  if (clear_glass.pixels) {
    std::snprintf(buffer, sizeof(buffer),
                  "; clear glass: %.2f holes, %.2f read behind, %.2f read the glass",
                  clear_glass.Share(clear_glass.holes), clear_glass.Share(clear_glass.through),
                  clear_glass.Share(clear_glass.surface));
    text += buffer;
  }
  return text;
}

namespace {

// synth.json: how the capture was made (the options, the sensor model) and what the sensor saw.
nlohmann::ordered_json SynthJson(const SynthOptions& options, const SynthSummary& summary) {
  nlohmann::ordered_json j;
  j["scene"] = options.scene;
  j["seed"] = options.seed;
  j["frames"] = options.frames;
  j["loop"] = options.loop;
  j["fps"] = options.fps;
  j["kinect"] = {{"projector_baseline_m", options.kinect.projector_baseline_m},
                 {"min_depth_m", options.kinect.min_depth_m},
                 {"max_depth_m", options.kinect.max_depth_m},
                 {"noise_sigma_m", "a + b (z - 0.4)^2"},
                 {"noise_a_m", options.kinect.noise_a_m},
                 {"noise_b_per_m", options.kinect.noise_b_per_m},
                 {"ir_return_probability", options.kinect.ir_return_probability},
                 {"glass_surface_probability", options.kinect.glass_surface_probability},
                 {"glass_surface_exponent", options.kinect.glass_surface_exponent},
                 {"glass_hole_probability", options.kinect.glass_hole_probability},
                 {"glass_hole_exponent", options.kinect.glass_hole_exponent},
                 {"glass_through_offset_m", options.kinect.glass_through_offset_m},
                 {"glass_through_sigma_m", options.kinect.glass_through_sigma_m},
                 {"glass_patch_px", options.kinect.glass_patch_px}};
  j["materials"] = {"diffuse", "glossy", "dark", "textured_glass", "clear_glass"};
  j["sensor_hole_fraction"] = summary.hole_fraction;
  // What the sensor saw on clear glass, beside the truth (gt/depth is the glass's own surface).
  const ClearGlassStats& glass = summary.clear_glass;
  j["clear_glass_sensor"] = {{"pixels", glass.pixels},
                             {"hole", glass.Share(glass.holes)},
                             {"reads_behind", glass.Share(glass.through)},
                             {"reads_surface", glass.Share(glass.surface)}};
  j["seconds_per_frame"] = summary.seconds_per_frame;
  return j;
}

}  // namespace

SynthSummary GenerateDataset(const SynthOptions& options, const std::string& out_dir,
                             const std::function<void(int, int)>& progress) {
  std::string problem;
  if (!options.Check(&problem)) throw InputError(out_dir, "bad synth options: " + problem);
  const fs::path stage = StageFolder(out_dir);
  std::error_code ec;
  for (const char* sub : {"raw", "gt/depth", "gt/visible_depth", "gt/label", "gt/holes"}) {
    fs::create_directories(stage / sub, ec);
    if (ec) throw InputError(out_dir, "cannot create output folder: " + ec.message());
  }
  // Anything that goes wrong below removes the staging folder.
  struct Cleanup {
    fs::path path;
    bool armed = true;
    ~Cleanup() {
      std::error_code e;
      if (armed) fs::remove_all(path, e);
    }
  } cleanup{stage};

  const auto start = std::chrono::steady_clock::now();
  const Scene scene = Scene::Make(options.scene, options.seed);
  const Camera camera = SynthCamera();
  const CameraFile camera_file = SynthCameraFile();
  const std::vector<SE3> poses = MakeTrajectory(scene, options);

  SynthSummary summary;
  Trajectory groundtruth;
  std::ostringstream index;
  size_t hole_pixels = 0, pixels = 0;
  {
    TumFolderSink sink((stage / "tum").string(), camera_file);
    for (int i = 0; i < options.frames; ++i) {
      SynthFrame f = RenderFrame(scene, camera, poses[i], options.kinect, options.seed, i);
      const double t = i / options.fps;
      const std::string ts = TimeText(t);
      RgbdFrame frame = ToRgbdFrame(f, i);
      frame.timestamp = frame.color_timestamp = t;
      frame.timestamp_text = ts;
      sink.Write(frame);
      const std::string counter = std::to_string(i);
      WriteRawPgm((stage / "raw" / ("d-" + ts + "-" + counter + ".pgm")).string(), f.raw_disparity);
      WriteImage((stage / "raw" / ("r-" + ts + "-" + counter + ".ppm")).string(), f.color);
      index << "d-" << ts << "-" << counter << ".pgm\n"
            << "r-" << ts << "-" << counter << ".ppm\n";
      WriteImage((stage / "gt/depth" / (ts + ".png")).string(), MetresToPng(f.true_depth));
      WriteImage((stage / "gt/visible_depth" / (ts + ".png")).string(),
                 MetresToPng(f.visible_depth));
      WriteImage((stage / "gt/label" / (ts + ".png")).string(), f.label);
      WriteImage((stage / "gt/holes" / (ts + ".png")).string(), f.hole_reason);
      groundtruth.push_back({t, ts, poses[i]});
      hole_pixels += cv::countNonZero(f.raw_disparity == DepthConvention::kKinectNoReturn);
      summary.clear_glass += CountClearGlass(f);
      pixels += f.raw_disparity.total();
      if (progress) progress(i + 1, options.frames);
    }
    sink.Close();
  }
  // Lift the TUM part to the top of the folder.
  for (const auto& e : fs::directory_iterator(stage / "tum"))
    fs::rename(e.path(), stage / e.path().filename());
  fs::remove(stage / "tum");
  WriteTextFileAtomically((stage / "raw/INDEX.txt").string(), index.str());
  SaveCameraFile((stage / "raw/camera.json").string(), camera_file);
  WriteTumTrajectory((stage / "groundtruth.txt").string(), groundtruth);
  scene.WritePly((stage / "scene.ply").string());

  summary.frames = options.frames;
  summary.seconds_per_frame =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() /
      options.frames;
  summary.hole_fraction = pixels ? static_cast<double>(hole_pixels) / pixels : 0.0;
  WriteTextFileAtomically((stage / "synth.json").string(),
                          JsonText(SynthJson(options, summary)) + "\n");

  PublishFolder(stage.string(), out_dir);
  cleanup.armed = false;
  return summary;
}

}  // namespace gf::synth
