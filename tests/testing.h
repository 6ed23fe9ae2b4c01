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
  c.distortion = {0.2624, -0.9531, -0.0054, 0.0026, 1.1633};
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
