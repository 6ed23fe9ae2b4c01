#include "acquisition/azure_kinect_mkv.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgproc.hpp>

#include "acquisition/errors.h"
#include "tests/k4a_mkv_writer.h"
#include "tests/testing.h"

namespace gf {
namespace {

namespace fs = std::filesystem;

// pyk4a's recording (tests/data/azure_kinect/README.md).
std::string RealRecording() {
  const fs::path p = fs::path(GF_SOURCE_DIR) / "tests/data/azure_kinect/recording.mkv";
  return fs::exists(p) ? p.string() : "";
}

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

// The message of the InputError that opening `path` throws ("" when none).
std::string OpenError(const std::string& path) {
  try {
    std::unique_ptr<FrameSource> source = OpenAzureKinectMkv(path, FrameSourceOptions());
    RgbdFrame frame;
    while (source->Next(&frame)) {
    }
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

SE3 ColorFromDepth() {
  return SE3(Eigen::Quaterniond(Eigen::AngleAxisd(0.0862, Eigen::Vector3d::UnitX())),
             Eigen::Vector3d(-0.0321, -0.0022, 0.0039));
}

TEST(AzureKinectCalibration, ReadsBackTheCamerasItWasWrittenWith) {
  const Camera depth = testing::AzureKinectNfovDepthCamera();
  const Camera color = testing::AzureKinect720pColorCamera();
  const std::string json =
      AzureKinectCalibrationJson(depth, "NFOV_UNBINNED", color, 720, ColorFromDepth());
  const CameraFile f = AzureKinectCalibration(json, "NFOV_UNBINNED", 720, "cal");
  ASSERT_TRUE(f.depth_camera.has_value());
  for (const auto& [got, want] : {std::pair(f.camera, color), std::pair(*f.depth_camera, depth)}) {
    EXPECT_EQ(got.width, want.width);
    EXPECT_EQ(got.height, want.height);
    EXPECT_NEAR(got.fx, want.fx, 1e-9);
    EXPECT_NEAR(got.cy, want.cy, 1e-9);
    for (int i = 0; i < 8; ++i) EXPECT_DOUBLE_EQ(got.distortion[i], want.distortion[i]) << i;
  }
  EXPECT_LT((f.color_from_depth.Matrix() - ColorFromDepth().Matrix()).norm(), 1e-12);
  EXPECT_FALSE(f.depth_registered_to_color);
  EXPECT_EQ(f.depth_scale, 1000.0);
  // The binned mode halves the depth camera: the same lens, every value in pixels halved.
  const CameraFile binned = AzureKinectCalibration(json, "NFOV_2X2BINNED", 720, "cal");
  EXPECT_EQ(binned.depth_camera->width, 320);
  EXPECT_NEAR(binned.depth_camera->fx, depth.fx / 2, 1e-9);
  EXPECT_NEAR(binned.depth_camera->cx + 0.5, (depth.cx + 0.5) / 2, 1e-9);
}

TEST(AzureKinectCalibration, RefusesWhatItCannotModelNamingIt) {
  const std::string json =
      AzureKinectCalibrationJson(testing::AzureKinectNfovDepthCamera(), "NFOV_UNBINNED",
                                 testing::AzureKinect720pColorCamera(), 720, SE3());
  auto error = [](const std::string& text, const std::string& mode, int height) {
    try {
      AzureKinectCalibration(text, mode, height, "rec.mkv");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error(json, "WFOV_2X2BINNED", 720).find("WFOV_2X2BINNED is not supported"),
            std::string::npos);
  EXPECT_NE(error(json, "NFOV_UNBINNED", 1000).find("unknown colour mode"), std::string::npos);
  EXPECT_NE(error("{\"CalibrationInformation\": ", "NFOV_UNBINNED", 720).find("rec.mkv: "),
            std::string::npos);
  std::string other_model = json;
  other_model.replace(other_model.find("BrownConrady"), 12, "Rational6KT");
  EXPECT_NE(error(other_model, "NFOV_UNBINNED", 720).find("is not supported"), std::string::npos);
  std::string no_colour = json;
  no_colour.replace(no_colour.find("LocationPV0"), 11, "LocationPV9");
  EXPECT_NE(error(no_colour, "NFOV_UNBINNED", 720).find("no camera"), std::string::npos);
}

// A real k4arecorder file: the factory calibration, MJPG colour, big-endian depth, device time.
TEST(AzureKinectMkv, ReadsARealRecording) {
  const std::string path = RealRecording();
  if (path.empty()) GTEST_SKIP() << "tests/data/azure_kinect/recording.mkv absent";
  std::unique_ptr<FrameSource> source = OpenAzureKinectMkv(path, FrameSourceOptions());
  EXPECT_EQ(source->Kind(), "azure_kinect_mkv");
  ASSERT_EQ(source->FrameCount(), 1);
  const CameraFile& cf = source->camera_file();
  EXPECT_EQ(cf.camera.width, 1280);
  EXPECT_NEAR(cf.camera.fx, 611.795, 1e-3);
  ASSERT_TRUE(cf.depth_camera.has_value());
  EXPECT_EQ(cf.depth_camera->height, 576);
  EXPECT_NEAR(cf.depth_camera->distortion[5], 0.8897, 1e-4);  // k4
  EXPECT_NEAR(cf.color_from_depth.translation().x(), -0.0321, 1e-4);
  RgbdFrame f;
  ASSERT_TRUE(source->Next(&f));
  EXPECT_EQ(f.timestamp_text, "0.800222");  // block 463945 us + K4A_START_OFFSET_NS 336277000
  EXPECT_EQ(f.color.size(), cv::Size(1280, 720));
  EXPECT_EQ(f.depth.size(), cv::Size(1280, 720));
  // A mug on a desk 1-2 m away: most of the depth camera's view has depth.
  std::vector<float> z;
  for (auto it = f.depth.begin<float>(); it != f.depth.end<float>(); ++it)
    if (*it > 0) z.push_back(*it);
  ASSERT_GT(z.size(), 300000u);
  std::nth_element(z.begin(), z.begin() + z.size() / 2, z.end());
  EXPECT_GT(z[z.size() / 2], 1.0);
  EXPECT_LT(z[z.size() / 2], 2.5);
  EXPECT_FALSE(source->Next(&f));
}

TEST(AzureKinectMkv, DamagedFilesAreInputErrorsNamingTheFile) {
  const std::string path = RealRecording();
  if (path.empty()) GTEST_SKIP() << "tests/data/azure_kinect/recording.mkv absent";
  testing::TempDir dir;
  const std::string bytes = ReadBytes(path);
  const std::string cut = dir / "cut.mkv", head = dir / "head.mkv", empty = dir / "empty.mkv",
                    other = dir / "other.mkv";
  WriteBytes(cut, bytes.substr(0, bytes.size() / 2));
  WriteBytes(head, bytes.substr(0, 300));
  WriteBytes(empty, "");
  WriteBytes(other, "P5\n2 2\n255\n\x01\x02\x03\x04");
  for (const std::string& p : {cut, head, empty, other, dir / "missing.mkv"}) {
    const std::string error = OpenError(p);
    EXPECT_EQ(error.rfind(p + ": ", 0), 0u) << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  }
}

// A recording written in the test: every frame, its device time, its depth (a plane at a known
// distance), its lossless colour, and a frame without colour left out.
TEST(AzureKinectMkv, ReadsWhatWasWritten) {
  testing::TempDir dir;
  const Camera depth_camera = testing::AzureKinectNfovDepthCamera();
  const Camera color_camera = testing::AzureKinect720pColorCamera();
  testing::K4aMkvOptions options;
  options.color_format = "BGRA";
  options.start_offset_ns = 5'000'123'000;
  options.calibration_json =
      AzureKinectCalibrationJson(depth_camera, "NFOV_UNBINNED", color_camera, 720, SE3());
  std::vector<cv::Mat> colors;
  {
    testing::K4aMkvWriter writer(dir / "rec.mkv", options);
    for (int i = 0; i < 5; ++i) {
      testing::K4aMkvFrame frame;
      frame.time_us = i * 33333;
      frame.depth_mm = cv::Mat(576, 640, CV_16UC1, cv::Scalar(1000 + 100 * i));
      cv::Mat color(720, 1280, CV_8UC3);
      cv::randu(color, 0, 255);
      colors.push_back(color);
      if (i != 3) frame.color_bgr = color;  // frame 3: colour dropped
      writer.Write(frame);
    }
    writer.Finish();
  }
  std::unique_ptr<FrameSource> source = OpenAzureKinectMkv(dir / "rec.mkv", FrameSourceOptions());
  ASSERT_EQ(source->FrameCount(), 4);
  RgbdFrame f;
  for (int i : {0, 1, 2, 4}) {
    ASSERT_TRUE(source->Next(&f)) << i;
    const int64_t us = 5'000'123 + i * 33333;
    EXPECT_EQ(f.timestamp_text, std::to_string(us / 1000000) + "." +
                                    std::string(6 - std::to_string(us % 1000000).size(), '0') +
                                    std::to_string(us % 1000000));
    EXPECT_EQ(cv::norm(f.color, colors[i], cv::NORM_INF), 0.0) << i;
    // The plane z = const stays at its depth through an identity extrinsic.
    cv::Mat valid = f.depth > 0;
    EXPECT_GT(cv::countNonZero(valid), 600000) << i;
    double lo = 0, hi = 0;
    cv::minMaxLoc(f.depth, nullptr, &hi);
    cv::minMaxLoc(f.depth, &lo, nullptr, nullptr, nullptr, valid);
    EXPECT_NEAR(lo, 1.0 + 0.1 * i, 1e-6) << i;
    EXPECT_NEAR(hi, 1.0 + 0.1 * i, 1e-6) << i;
  }
  EXPECT_FALSE(source->Next(&f));
}

TEST(AzureKinectMkv, JpegColourAndATruncatedFile) {
  testing::TempDir dir;
  testing::K4aMkvOptions options;
  options.calibration_json = AzureKinectCalibrationJson(
      testing::AzureKinectNfovDepthCamera(), "NFOV_UNBINNED",
      testing::AzureKinect720pColorCamera(), 720, ColorFromDepth());
  cv::Mat color(720, 1280, CV_8UC3);
  cv::randu(color, 0, 255);
  cv::GaussianBlur(color, color, cv::Size(31, 31), 8);  // smooth: JPEG keeps it well
  {
    testing::K4aMkvWriter writer(dir / "rec.mkv", options);
    for (int i = 0; i < 20; ++i)
      writer.Write({i * 33333, cv::Mat(576, 640, CV_16UC1, cv::Scalar(1500)), color});
    writer.Finish();
  }
  std::unique_ptr<FrameSource> source = OpenAzureKinectMkv(dir / "rec.mkv", FrameSourceOptions());
  ASSERT_EQ(source->FrameCount(), 20);
  RgbdFrame f;
  ASSERT_TRUE(source->Next(&f));
  EXPECT_LT(cv::norm(f.color, color, cv::NORM_L1) / color.total() / 3, 2.0);
  // Cut at 60%: the file reads to its end without an error from libavformat, but its blocks end
  // long before its stated duration.
  const std::string bytes = ReadBytes(dir / "rec.mkv");
  WriteBytes(dir / "cut.mkv", bytes.substr(0, bytes.size() * 6 / 10));
  const std::string error = OpenError(dir / "cut.mkv");
  EXPECT_EQ(error.rfind(dir / "cut.mkv: ", 0), 0u) << error;
  EXPECT_TRUE(error.find("truncated") != std::string::npos ||
              error.find("damaged") != std::string::npos)
      << error;
}

}  // namespace
}  // namespace gf
