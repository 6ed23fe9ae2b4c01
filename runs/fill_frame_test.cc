#include "runs/fill_frame.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "acquisition/errors.h"
#include "tests/testing.h"

namespace gf {
namespace {

void WriteCamera(const std::string& path, int width, int height, double focal) {
  std::ofstream(path) << "{\"width\": " << width << ", \"height\": " << height
                      << ", \"fx\": " << focal << ", \"fy\": " << focal
                      << ", \"cx\": " << 0.5 * (width - 1) << ", \"cy\": " << 0.5 * (height - 1)
                      << ", \"depth_scale\": 1000}";
}

// A tilted table 0.7 m ahead, every pixel read, as metres.
cv::Mat Table(int width, int height, double focal) {
  cv::Mat depth(height, width, CV_32F);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      depth.at<float>(y, x) = static_cast<float>(0.7 / (1 + 0.6 * (y - 0.5 * height) / focal));
  return depth;
}

TEST(ReadMetricDepth, ReadsPngUnitsAndFileStorageMetres) {
  const testing::TempDir dir;
  const cv::Mat depth = Table(64, 48, 60);
  cv::Mat mm;
  depth.convertTo(mm, CV_16U, 1000);
  ASSERT_TRUE(cv::imwrite(dir / "d.png", mm));
  const cv::Mat png = ReadMetricDepth(dir / "d.png", 1000);
  ASSERT_EQ(png.type(), CV_32FC1);
  EXPECT_NEAR(png.at<float>(10, 10), depth.at<float>(10, 10), 0.001);
  cv::Mat with_nan = depth.clone();
  with_nan.at<float>(5, 5) = NAN;
  {
    cv::FileStorage fs(dir / "d.xml.gz", cv::FileStorage::WRITE);
    fs << "depth_image" << with_nan;
  }
  const cv::Mat stored = ReadMetricDepth(dir / "d.xml.gz", 1000);
  EXPECT_FLOAT_EQ(stored.at<float>(10, 10), depth.at<float>(10, 10));
  EXPECT_EQ(stored.at<float>(5, 5), 0.f);  // NaN: a hole
}

TEST(RunFillFrame, BadInputNamesTheFile) {
  const testing::TempDir dir;
  WriteCamera(dir / "camera.json", 64, 48, 60);
  cv::Mat mm;
  Table(64, 48, 60).convertTo(mm, CV_16U, 1000);
  ASSERT_TRUE(cv::imwrite(dir / "d.png", mm));
  ASSERT_TRUE(cv::imwrite(dir / "c.png", cv::Mat(48, 64, CV_8UC3, cv::Scalar(90, 90, 90))));
  ASSERT_TRUE(cv::imwrite(dir / "small.png", cv::Mat(24, 32, CV_8UC3, cv::Scalar(0))));
  FillFrameOptions o;
  o.color_file = dir / "c.png", o.depth_file = dir / "missing.png";
  o.camera_file = dir / "camera.json", o.out_dir = dir / "out";
  try {
    RunFillFrame(o);
    FAIL() << "no error for a missing depth file";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), dir / "missing.png");
  }
  o.depth_file = dir / "d.png", o.color_file = dir / "small.png";
  EXPECT_THROW(RunFillFrame(o), InputError);
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));  // nothing written on bad input
  o.color_file = dir / "c.png";
  std::ofstream(dir / "a_file") << "the user's";
  o.out_dir = dir / "a_file";  // an output folder that is a file: refused, the file kept
  try {
    RunFillFrame(o);
    FAIL() << "no error for an output folder that is a file";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), dir / "a_file");
  }
  std::string kept;
  std::getline(std::ifstream(dir / "a_file"), kept);
  EXPECT_EQ(kept, "the user's");
  o.out_dir = dir / "out";
  const FillFrameSummary s = RunFillFrame(o);  // a bare table: no glass, depth as read
  EXPECT_TRUE(s.result.plane_found);
  EXPECT_EQ(s.result.replaced_pixels, 0);
  const cv::Mat out = cv::imread(dir / "out/depth_filled.png", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(out.type(), CV_16UC1);
  EXPECT_EQ(cv::countNonZero(out != mm), 0);
  for (const char* name : {"glass_mask.png", "glass_overlay.png", "fill_frame.json"})
    EXPECT_TRUE(std::filesystem::exists(dir / ("out/" + std::string(name)))) << name;
}

TEST(ParseBox, TakesXYWidthHeightAndNamesWhatIsWrong) {
  EXPECT_EQ(ParseBox("10,20,30,40", "--box"), cv::Rect(10, 20, 30, 40));
  for (const char* bad : {"10,20,30", "10,20,0,40", "a,b,c,d", "1,2,3,4,5"})
    EXPECT_THROW(ParseBox(bad, "--box"), InputError) << bad;
}

// Real D435 frames of clear objects (ClearGrasp), each object given by its mask, or by a box
// round it as a person would draw one (its extent and a tenth more each way): the glass is cut
// out of the box (IoU at least 0.8 with the objects' mask), and the standing shape puts more of
// their pixels within 1 cm of the true surface than the sensor had; with the mask, nothing
// outside it changes.
TEST(RunFillFrame, RealClearObjectsGivenOrBoxed) {
  GF_REQUIRE_DATASET(root, "glass_real_frames/cleargrasp_d435");
  const testing::TempDir dir;
  std::ofstream(dir / "camera.json")  // camera_intrinsics.yaml
      << R"({"width": 1280, "height": 720, "fx": 921, "fy": 921, "cx": 642, "cy": 359,
             "depth_scale": 1000})";
  for (const std::string id : {"000000080", "000000123"})
    for (const bool boxed : {false, true}) {
      FillFrameOptions o;
      o.color_file = root + "/" + id + "-transparent-rgb-img.jpg";
      o.depth_file = root + "/" + id + "-transparent-depth-img.exr";
      o.mask_file = root + "/" + id + "-mask.png";
      o.camera_file = dir / "camera.json", o.out_dir = dir / id;
      const cv::Mat mask = cv::imread(o.mask_file, cv::IMREAD_GRAYSCALE) > 0;
      if (boxed) {
        cv::Mat labels, stats, centroids;
        const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids);
        for (int i = 1; i < n; ++i) {
          const cv::Rect r(stats.at<int>(i, 0), stats.at<int>(i, 1), stats.at<int>(i, 2),
                           stats.at<int>(i, 3));
          if (stats.at<int>(i, cv::CC_STAT_AREA) < 500) continue;
          const int mx = r.width / 10 + 3, my = r.height / 10 + 3;
          o.boxes.emplace_back(r.x - mx, r.y - my, r.width + 2 * mx, r.height + 2 * my);
        }
        o.mask_file.clear();
      }
      const FillFrameSummary s = RunFillFrame(o);
      const cv::Mat raw = ReadMetricDepth(o.depth_file, 1000);
      const cv::Mat truth = ReadMetricDepth(root + "/" + id + "-opaque-depth-img.exr", 1000);
      const cv::Mat found = s.result.glass_mask > 0;
      EXPECT_GT(cv::countNonZero(found & mask), 0.8 * cv::countNonZero(found | mask)) << id;
      int known = 0, raw_within = 0, filled_within = 0;
      for (int y = 0; y < raw.rows; ++y)
        for (int x = 0; x < raw.cols; ++x) {
          if (!mask.at<uint8_t>(y, x) || truth.at<float>(y, x) <= 0) continue;
          ++known;
          const float t = truth.at<float>(y, x);
          raw_within += std::abs(raw.at<float>(y, x) - t) < 0.01f;
          filled_within += std::abs(s.result.depth_filled.at<float>(y, x) - t) < 0.01f;
        }
      ASSERT_GT(known, 1000) << id;
      EXPECT_GT(filled_within, raw_within) << id << (boxed ? " boxed" : "");
      if (!boxed) EXPECT_EQ(cv::countNonZero((s.result.depth_filled != raw) & ~mask), 0) << id;
    }
}

}  // namespace
}  // namespace gf
