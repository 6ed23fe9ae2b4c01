// Helpers shared by GlassFusion tests (header-only, tests only).
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "acquisition/camera.h"

namespace gf::testing {

// The colour camera of TUM fr1 (640x480, as the dataset's camera.json lists it), lens distortion
// included.
inline Camera TumFr1Camera() {
  Camera c;
  c.fx = 517.3;
  c.fy = 516.5;
  c.cx = 318.6;
  c.cy = 255.3;
  c.distortion = {0.2624, -0.9531, -0.0054, 0.0026, 1.1633, 0, 0, 0};
  return c;
}

// The depth camera of an Azure Kinect DK in NFOV_UNBINNED mode (640x576; the calibration of
// pyk4a's test recording, tests/data/azure_kinect): OpenCV's rational model, strong barrel
// distortion (k1 0.55 over k4 0.89).
inline Camera AzureKinectNfovDepthCamera() {
  Camera c;
  c.width = 640;
  c.height = 576;
  c.fx = 504.6076;
  c.fy = 504.7325;
  c.cx = 332.7811;
  c.cy = 348.8297;
  c.distortion = {0.54794, -0.0209714, 2.05575e-05, -7.21042e-05,
                  -0.00265223, 0.889679, 0.0861302, -0.0139104};
  return c;
}

// The colour camera of the same device in 720p mode (1280x720).
inline Camera AzureKinect720pColorCamera() {
  Camera c;
  c.width = 1280;
  c.height = 720;
  c.fx = 611.7953;
  c.fy = 611.9270;
  c.cx = 639.3043;
  c.cy = 365.8529;
  c.distortion = {0.330121, -2.4894, -0.000161782, -0.000129445, 1.45367, 0.208912, -2.30292, 1.37513};
  return c;
}

// A pinhole camera of width x height pixels, focal length `focal` (pixels) both ways, the
// principal point at the image's centre, no distortion.
inline Camera PinholeCamera(int width, int height, double focal) {
  Camera c;
  c.width = width;
  c.height = height;
  c.fx = c.fy = focal;
  c.cx = 0.5 * (width - 1);
  c.cy = 0.5 * (height - 1);
  return c;
}

// Path of a folder in ../shared/datasets, or "" when the datasets are not on this machine.
inline std::string SharedDataset(const std::string& name) {
  const std::filesystem::path p = std::filesystem::path(GF_SHARED_DATASETS) / name;
  return std::filesystem::exists(p) ? p.string() : std::string();
}

// A fresh empty folder under the system temp dir, removed when the object goes away.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string("gf-") + (info ? info->name() : "test") + "-";
    path_ = std::filesystem::temp_directory_path() /
            (name + std::to_string(::getpid()) + "-" + std::to_string(counter_++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string path() const { return path_.string(); }
  std::string operator/(const std::string& name) const { return (path_ / name).string(); }

 private:
  static inline int counter_ = 0;
  std::filesystem::path path_;
};

}  // namespace gf::testing

// Skips the test (never passes silently) when a dataset of ../shared/datasets is absent.
#define GF_REQUIRE_DATASET(var, name)                         \
  const std::string var = ::gf::testing::SharedDataset(name); \
  if (var.empty()) GTEST_SKIP() << "dataset " << name << " not found under " GF_SHARED_DATASETS
