#include "acquisition/depth.h"

#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "acquisition/errors.h"
#include "acquisition/image_io.h"
#include "tests/testing.h"

namespace gf {
namespace {

TEST(DepthConvention, KinectRawMarks2047AsNoReturnAndRoundTrips) {
  const DepthConvention k = DepthConvention::KinectV1Raw11Bit();
  EXPECT_TRUE(k.IsNoReturn(0x7FF));
  EXPECT_FALSE(k.IsNoReturn(0));
  EXPECT_EQ(k.ToMetres(0x7FF), 0.0);
  EXPECT_EQ(k.NoReturnValue(), 2047);
  // Burrus' model: raw 600 -> 1 / (3.3309495161 - 1.84266096) = 0.6719 m.
  EXPECT_NEAR(k.ToMetres(600), 1.0 / (3.3309495161 - 0.0030711016 * 600), 1e-12);
  // Depth grows monotonically with disparity value, and metres -> raw -> metres stays within the
  // quantisation step (disparity is integer, so the step grows with depth squared).
  double previous = 0;
  for (int raw = 300; raw < 1080; ++raw) {
    const double m = k.ToMetres(static_cast<uint16_t>(raw));
    EXPECT_GT(m, previous);
    previous = m;
    EXPECT_EQ(k.FromMetres(m), raw);
  }
  EXPECT_EQ(k.FromMetres(0.0), 2047);
  EXPECT_EQ(k.FromMetres(1e6), 2047);  // beyond the model's asymptote
}

TEST(DepthConvention, ZeroIsTheHoleInLinearStreamsAnd2047IsAValidDepth) {
  const DepthConvention mm = DepthConvention::Millimetres();
  EXPECT_TRUE(mm.IsNoReturn(0));
  EXPECT_FALSE(mm.IsNoReturn(2047));
  EXPECT_DOUBLE_EQ(mm.ToMetres(2047), 2.047);
  const DepthConvention tum = DepthConvention::ScaledUnits(5000);
  EXPECT_DOUBLE_EQ(tum.ToMetres(5000), 1.0);
  EXPECT_EQ(tum.FromMetres(1.2345), 6173);
  EXPECT_EQ(tum.Name(), "scaled_units(5000)");
  EXPECT_EQ(DepthConvention::FromDepthScale(1000), DepthConvention::Millimetres());
  EXPECT_THROW(DepthConvention::ScaledUnits(0), std::logic_error);
}

TEST(ConvertDepth, ClassifiesNoReturnAndOutOfRange) {
  cv::Mat raw = (cv::Mat_<uint16_t>(1, 5) << 0, 5000, 500, 65000, 10000);
  cv::Mat depth, holes;
  DepthConversionOptions options;
  options.min_depth_m = 0.3;
  options.max_depth_m = 10.0;
  ConvertDepth(raw, DepthConvention::ScaledUnits(5000), options, &depth, &holes);
  EXPECT_EQ(holes.at<uint8_t>(0), static_cast<uint8_t>(HoleCode::kNoReturn));
  EXPECT_EQ(holes.at<uint8_t>(1), static_cast<uint8_t>(HoleCode::kValid));
  EXPECT_EQ(holes.at<uint8_t>(2), static_cast<uint8_t>(HoleCode::kOutOfRange));  // 0.1 m
  EXPECT_EQ(holes.at<uint8_t>(3), static_cast<uint8_t>(HoleCode::kOutOfRange));  // 13 m
  EXPECT_FLOAT_EQ(depth.at<float>(1), 1.0f);
  EXPECT_FLOAT_EQ(depth.at<float>(4), 2.0f);
  EXPECT_EQ(depth.at<float>(0), 0.f);
  EXPECT_EQ(depth.at<float>(2), 0.f);
  const HoleStats s = CountHoles(holes);
  EXPECT_EQ(s.pixels, 5u);
  EXPECT_EQ(s.no_return, 1u);
  EXPECT_EQ(s.out_of_range, 2u);
  EXPECT_DOUBLE_EQ(s.Fraction(), 0.6);
}

TEST(ConvertDepth, MetricDepthRoundTripsThroughRawUnits) {
  cv::Mat depth(4, 4, CV_32FC1);
  cv::randu(depth, 0.5, 4.0);
  depth.at<float>(0, 0) = 0.f;
  cv::Mat back, holes;
  ConvertDepth(DepthToRaw(depth, DepthConvention::ScaledUnits(5000)),
               DepthConvention::ScaledUnits(5000), {}, &back, &holes);
  EXPECT_EQ(holes.at<uint8_t>(0, 0), static_cast<uint8_t>(HoleCode::kNoReturn));
  EXPECT_LE(cv::norm(back, depth, cv::NORM_INF), 0.5 / 5000 + 1e-6);
}

TEST(KinectRaw, NyuFrameIsLittleEndianElevenBitWithSevenPercentHoles) {
  GF_REQUIRE_DATASET(raw_dir, "kinect_v1_raw");
  const std::string path = raw_dir + "/NYU_depth.pgm";
  const cv::Mat raw = ReadPgm16(path);
  ASSERT_EQ(raw.cols, 640);
  ASSERT_EQ(raw.rows, 480);
  const DepthConvention k = DepthConvention::KinectV1Raw11Bit();
  EXPECT_EQ(k.ValidateRaw(raw), "");
  const double holes_2047 = cv::countNonZero(raw == 2047) / static_cast<double>(raw.total());
  EXPECT_NEAR(holes_2047, 0.072, 0.001);

  cv::Mat depth, mask;
  ConvertDepth(raw, k, {}, &depth, &mask);
  const HoleStats s = CountHoles(mask);
  EXPECT_NEAR(static_cast<double>(s.no_return) / s.pixels, 0.0723, 0.0005);
  // Valid pixels of an indoor NYU scene lie between about 1 and 8 metres.
  double lo = 0, hi = 0;
  cv::minMaxLoc(depth, nullptr, &hi);
  cv::minMaxLoc(depth, &lo, nullptr, nullptr, nullptr, mask == 0);
  EXPECT_GT(lo, 1.0);
  EXPECT_LT(hi, 8.0);

  // Read against its byte order, the same file is not 11-bit disparity, and validation says so.
  const cv::Mat swapped = ReadPgm16(path, PgmByteOrder::kBigEndian);
  EXPECT_NE(k.ValidateRaw(swapped), "");
}

TEST(KinectRaw, TumMillimetreDepthIsNotMistakenForDisparity) {
  GF_REQUIRE_DATASET(tum, "tum_fr1_xyz_head");
  const cv::Mat raw = ReadDepthImage(tum + "/depth/1305031102.160407.png");
  EXPECT_NE(DepthConvention::KinectV1Raw11Bit().ValidateRaw(raw).find("exceed 2047"),
            std::string::npos);
  cv::Mat depth, mask;
  ConvertDepth(raw, DepthConvention::ScaledUnits(5000), {}, &depth, &mask);
  const HoleStats s = CountHoles(mask);
  EXPECT_EQ(s.no_return, static_cast<size_t>(cv::countNonZero(raw == 0)));
  EXPECT_GT(s.Fraction(), 0.15);
  EXPECT_LT(s.Fraction(), 0.35);
}

TEST(ImageIo, BadDepthFilesGiveErrorsNamingTheFile) {
  testing::TempDir dir;
  // 8-bit PNG where 16-bit depth is expected.
  const std::string eight = dir / "eight.png";
  cv::imwrite(eight, cv::Mat(4, 4, CV_8UC1, cv::Scalar(7)));
  try {
    ReadDepthImage(eight);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(eight), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("8-bit"), std::string::npos);
  }
  // Corrupt PNG.
  const std::string corrupt = dir / "corrupt.png";
  std::ofstream(corrupt) << "\x89PNG garbage";
  EXPECT_THROW(ReadDepthImage(corrupt), InputError);
  // Truncated PGM.
  const std::string truncated = dir / "truncated.pgm";
  std::ofstream(truncated, std::ios::binary) << "P5 640 480 65535\n" << std::string(1000, '\x01');
  try {
    ReadPgm16(truncated);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ReadDepthImage(dir / "missing.png"), InputError);
}

}  // namespace
}  // namespace gf

namespace gf {
namespace {

TEST(SortedDepthSample, KeepsMeasuredPixelsOnTheGridInOrder) {
  cv::Mat depth(4, 6, CV_32FC1, cv::Scalar(0.f));
  depth.at<float>(0, 0) = 2.f;
  depth.at<float>(0, 2) = 1.f;
  depth.at<float>(2, 4) = 3.f;
  depth.at<float>(1, 1) = 9.f;  // off the step-2 grid
  EXPECT_EQ(SortedDepthSample(depth, 2), (std::vector<float>{1.f, 2.f, 3.f}));
  EXPECT_EQ(SortedDepthSample(depth, 1).size(), 4u);
}

}  // namespace
}  // namespace gf
