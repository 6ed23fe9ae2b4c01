#include "acquisition/frame_sink.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "acquisition/errors.h"
#include "acquisition/frame_source.h"
#include "tests/testing.h"

namespace gf {
namespace {

namespace fs = std::filesystem;

// The smallest image GlassFusion reads (32x24), with a plausible 44 x 33 degree field of view.
CameraFile SmallCamera() {
  CameraFile c;
  c.camera.width = 32;
  c.camera.height = 24;
  c.camera.fx = c.camera.fy = 40;
  c.camera.cx = 15.5;
  c.camera.cy = 11.5;
  return c;
}

RgbdFrame SmallFrame(int i) {
  RgbdFrame f;
  f.index = i;
  f.timestamp = 100.0 + i / 30.0;
  f.color_timestamp = f.timestamp + 0.004;
  f.color = cv::Mat(24, 32, CV_8UC3, cv::Scalar(10 * i, 20, 30));
  f.depth = cv::Mat(24, 32, CV_32FC1, cv::Scalar(1.0f + 0.1234f * i));
  f.depth.at<float>(0, 0) = 0.f;  // a hole survives the round trip
  f.hole_mask = cv::Mat(24, 32, CV_8UC1, cv::Scalar(0));
  return f;
}

TEST(TumFolderSink, WritesAFolderTheTumReaderReadsBack) {
  testing::TempDir dir;
  const std::string out = dir / "capture";
  {
    TumFolderSink sink(out, SmallCamera());
    for (int i = 0; i < 3; ++i) sink.Write(SmallFrame(i));
    EXPECT_FALSE(fs::exists(out)) << "the folder must appear only when complete";
    sink.Close();
  }
  auto source = OpenFrameSource(out, {});
  EXPECT_EQ(source->Kind(), "tum");
  EXPECT_EQ(source->FrameCount().value(), 3);
  EXPECT_EQ(source->camera().fx, 40.0);
  RgbdFrame f;
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(source->Next(&f));
    const RgbdFrame expected = SmallFrame(i);
    EXPECT_NEAR(f.timestamp, expected.timestamp, 1e-6);
    EXPECT_NEAR(f.color_timestamp, expected.color_timestamp, 1e-6);
    EXPECT_EQ(cv::norm(f.color, expected.color, cv::NORM_INF), 0.0);
    EXPECT_LE(cv::norm(f.depth, expected.depth, cv::NORM_INF), 0.5 / 5000 + 1e-6);
    EXPECT_EQ(f.hole_mask.at<uint8_t>(0, 0), static_cast<uint8_t>(HoleCode::kNoReturn));
  }
  EXPECT_FALSE(source->Next(&f));
}

TEST(TumFolderSink, LeavesNothingBehindWhenNotClosed) {
  testing::TempDir dir;
  const std::string out = dir / "capture";
  {
    TumFolderSink sink(out, SmallCamera());
    sink.Write(SmallFrame(0));
  }  // e.g. an exception unwound the capture
  EXPECT_TRUE(fs::is_empty(dir.path())) << "partial output left in " << dir.path();
}

TEST(TumFolderSink, RefusesANonEmptyFolderAndFramesWithoutColour) {
  testing::TempDir dir;
  std::ofstream(dir / "keep.txt") << "precious";
  EXPECT_THROW(TumFolderSink(dir.path(), SmallCamera()), InputError);
  EXPECT_TRUE(fs::exists(dir / "keep.txt"));
  TumFolderSink sink(dir / "new", SmallCamera());
  RgbdFrame f = SmallFrame(0);
  f.color.release();
  EXPECT_THROW(sink.Write(f), InputError);
}

}  // namespace
}  // namespace gf
