// Test tool: renders a synthetic scene as an Azure Kinect DK records it and writes it as a
// k4arecorder .mkv (tests/k4a_mkv_writer.h), with the colour camera's true trajectory.
//
// The device: colour in 720p (gf::testing::AzureKinect720pColorCamera, 1280x720), depth in
// NFOV_UNBINNED (gf::testing::AzureKinectNfovDepthCamera, 640x576), each rendered through its own
// lens (rational model); the depth camera sits at color_from_depth (ColorFromDepth()) from the
// colour camera, as on the device. The scene, the colour camera's path (the synthetic dataset's
// trajectory, world_from_color) and the sensor noise (the Kinect v1 model of datasets/synth.h)
// are those of `glassfusion synth`.
// Frame i has block time i * 33333 us (30 fps) and device time 1 s + that (K4A_START_OFFSET_NS).
// The ground truth (TUM) is world_from_color at each frame's device time in seconds.
//
// usage: gf_synth_to_mkv --scene NAME --frames N --seed S --out FILE.mkv --groundtruth FILE.txt
//                        [--color-format MJPG|BGRA]
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "acquisition/azure_kinect_mkv.h"
#include "acquisition/camera.h"
#include "acquisition/se3.h"
#include "acquisition/trajectory.h"
#include "datasets/scene.h"
#include "datasets/synth.h"
#include "tests/k4a_mkv_writer.h"
#include "tests/testing.h"

namespace {

constexpr const char* kUsage =
    "usage: gf_synth_to_mkv --scene NAME --frames N --seed S --out FILE.mkv "
    "--groundtruth FILE.txt [--color-format MJPG|BGRA]";
constexpr int64_t kFramePeriodUs = 33333;           // 30 fps, microseconds
constexpr int64_t kStartOffsetNs = 1'000'000'000;  // device time of block time 0, nanoseconds

// point_in_color = color_from_depth * point_in_depth: the depth camera's centre 3.2 cm along the
// colour camera's -x axis (about as on the device), turned 0.0012 rad about y. Metres.
gf::SE3 ColorFromDepth() {
  return gf::SE3(Eigen::Quaterniond(Eigen::AngleAxisd(0.0012, Eigen::Vector3d::UnitY())),
                 Eigen::Vector3d(-0.032083, -0.002205, 0.003884));
}

struct Arguments {
  std::string scene = "glass-table";
  int frames = 30;
  uint32_t seed = 1;
  std::string out;          // the .mkv
  std::string groundtruth;  // the TUM trajectory
  std::string color_format = "MJPG";
};

// Whether `text` is a whole decimal integer in [min, max].
bool ParseInteger(const std::string& text, long long min, long long max, long long* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  *value = std::strtoll(text.c_str(), &end, 10);
  return *end == '\0' && *value >= min && *value <= max;
}

// Fills `args` from the command line; returns "" or what is wrong, one line.
std::string ParseArguments(int argc, char** argv, Arguments* args) {
  for (int i = 1; i < argc; i += 2) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) return flag + " needs a value";
    const std::string value = argv[i + 1];
    long long number = 0;
    if (flag == "--scene") {
      args->scene = value;
    } else if (flag == "--frames") {
      if (!ParseInteger(value, 1, 100000, &number)) return "--frames must be 1-100000";
      args->frames = static_cast<int>(number);
    } else if (flag == "--seed") {
      if (!ParseInteger(value, 0, UINT32_MAX, &number)) return "--seed must be 0-4294967295";
      args->seed = static_cast<uint32_t>(number);
    } else if (flag == "--out") {
      args->out = value;
    } else if (flag == "--groundtruth") {
      args->groundtruth = value;
    } else if (flag == "--color-format") {
      if (value != "MJPG" && value != "BGRA") return "--color-format must be MJPG or BGRA";
      args->color_format = value;
    } else {
      return "unknown argument " + flag;
    }
  }
  if (args->out.empty() || args->groundtruth.empty()) return "--out and --groundtruth are needed";
  bool known_scene = false;
  for (const std::string& name : gf::synth::Scene::Names()) known_scene |= name == args->scene;
  if (!known_scene) return "unknown scene " + args->scene;
  return "";
}

// Device time of block time `time_us` as TUM text: seconds with exactly 6 decimals.
std::string DeviceTimeText(int64_t time_us) {
  const int64_t device_us = kStartOffsetNs / 1000 + time_us;
  char text[32];
  std::snprintf(text, sizeof(text), "%lld.%06lld", static_cast<long long>(device_us / 1000000),
                static_cast<long long>(device_us % 1000000));
  return text;
}

int Convert(const Arguments& args) {
  const gf::Camera color_camera = gf::testing::AzureKinect720pColorCamera();
  const gf::Camera depth_camera = gf::testing::AzureKinectNfovDepthCamera();
  const gf::SE3 color_from_depth = ColorFromDepth();

  gf::synth::SynthOptions synth;
  synth.scene = args.scene;
  synth.frames = args.frames;
  synth.seed = args.seed;
  const gf::synth::Scene scene = gf::synth::Scene::Make(synth.scene, synth.seed);
  const std::vector<gf::SE3> world_from_color = gf::synth::MakeTrajectory(scene, synth);

  gf::testing::K4aMkvOptions options;
  options.depth_mode = "NFOV_UNBINNED";
  options.color_height = 720;
  options.color_format = args.color_format;
  options.start_offset_ns = kStartOffsetNs;
  options.calibration_json = gf::AzureKinectCalibrationJson(depth_camera, "NFOV_UNBINNED",
                                                            color_camera, 720, color_from_depth);
  gf::testing::K4aMkvWriter writer(args.out, options);
  gf::Trajectory groundtruth;
  for (int i = 0; i < args.frames; ++i) {
    const gf::SE3 world_from_depth = world_from_color[i] * color_from_depth;
    gf::testing::K4aMkvFrame frame;
    frame.time_us = i * kFramePeriodUs;
    frame.color_bgr = gf::synth::RenderFrame(scene, color_camera, world_from_color[i],
                                             synth.kinect, synth.seed, i)
                          .color;
    const gf::synth::SynthFrame depth = gf::synth::RenderFrame(
        scene, depth_camera, world_from_depth, synth.kinect, synth.seed, i);
    // Metres (0 = hole) to millimetres, rounded; holes stay 0.
    gf::synth::ToRgbdFrame(depth, i).depth.convertTo(frame.depth_mm, CV_16UC1, 1000.0);
    writer.Write(frame);
    const std::string time_text = DeviceTimeText(frame.time_us);
    groundtruth.push_back({std::stod(time_text), time_text, world_from_color[i]});
    std::fprintf(stderr, "gf_synth_to_mkv: frame %d/%d\n", i + 1, args.frames);
  }
  writer.Finish();
  gf::WriteTumTrajectory(args.groundtruth, groundtruth);
  std::fprintf(stderr, "gf_synth_to_mkv: wrote %s and %s\n", args.out.c_str(),
               args.groundtruth.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::printf("%s\n", kUsage);
    return 0;
  }
  Arguments args;
  const std::string problem = ParseArguments(argc, argv, &args);
  if (!problem.empty()) {
    std::fprintf(stderr, "gf_synth_to_mkv: %s (%s)\n", problem.c_str(), kUsage);
    return 1;
  }
  try {
    return Convert(args);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gf_synth_to_mkv: error: %s\n", e.what());
    return 2;
  }
}
