#include "acquisition/frame_source.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "acquisition/errors.h"
#include "acquisition/image_io.h"
#include "tests/testing.h"

namespace gf {
namespace {

namespace fs = std::filesystem;

TEST(AssociateTimestamps, PairsOneToOneWithinTheWindow) {
  const std::vector<double> depth = {0.000, 0.033, 0.066, 0.100, 0.500};
  const std::vector<double> color = {0.010, 0.030, 0.070, 0.300};
  const auto pairs = AssociateTimestamps(depth, color, 0.02);
  // 0.033 takes 0.030 (3 ms) before 0.000 could; 0.000 then takes 0.010; 0.066 takes 0.070;
  // 0.100 and 0.500 have nothing within 20 ms.
  ASSERT_EQ(pairs.size(), 3u);
  EXPECT_EQ(pairs[0], (std::pair<size_t, size_t>(0, 0)));
  EXPECT_EQ(pairs[1], (std::pair<size_t, size_t>(1, 1)));
  EXPECT_EQ(pairs[2], (std::pair<size_t, size_t>(2, 2)));
}

TEST(TumFolder, ReadsAllFramesOfTheHeadSequence) {
  GF_REQUIRE_DATASET(tum, "tum_fr1_xyz_head");
  auto source = OpenFrameSource(tum, {});
  EXPECT_EQ(source->Kind(), "tum");
  // 150 depth and 150 colour images; as TUM's associate.py (20 ms), 144 pairs (checked in Python).
  EXPECT_EQ(source->FrameCount().value(), 144);
  auto* folder = dynamic_cast<FolderFrameSource*>(source.get());
  ASSERT_NE(folder, nullptr);
  EXPECT_EQ(folder->listed_depth, 150);
  EXPECT_EQ(folder->unmatched_depth, 6);
  EXPECT_DOUBLE_EQ(source->camera().fx, 517.3);
  EXPECT_EQ(source->depth_convention(), DepthConvention::ScaledUnits(5000));
  RgbdFrame frame;
  int count = 0;
  double previous = 0;
  while (source->Next(&frame)) {
    if (count == 0) {
      EXPECT_EQ(frame.timestamp_text, "1305031102.160407");
      EXPECT_NEAR(frame.color_timestamp, 1305031102.175304, 1e-6);
    }
    EXPECT_GT(frame.timestamp, previous);
    EXPECT_LT(std::abs(frame.color_timestamp - frame.timestamp), 0.02);
    previous = frame.timestamp;
    ASSERT_EQ(frame.depth.type(), CV_32FC1);
    ASSERT_EQ(frame.color.type(), CV_8UC3);
    EXPECT_EQ(frame.color.size(), cv::Size(640, 480));
    // Desk scene: valid depth between 0.5 and 5 m; hole mask agrees with zero depth.
    cv::Mat valid = frame.hole_mask == 0;
    double lo, hi;
    cv::minMaxLoc(frame.depth, &lo, &hi, nullptr, nullptr, valid);
    EXPECT_GT(lo, 0.5);
    EXPECT_LT(hi, 5.0);
    EXPECT_EQ(cv::countNonZero(frame.depth == 0), cv::countNonZero(~valid));
    ++count;
    if (count == 5) break;  // reading all 150 colour images adds nothing here
  }
  EXPECT_EQ(count, 5);
}

TEST(RedwoodFolder, ReadsIclMicroAndNoisyDepth) {
  GF_REQUIRE_DATASET(icl, "icl_livingroom1_micro");
  auto source = OpenFrameSource(icl, {});
  EXPECT_EQ(source->Kind(), "redwood");
  EXPECT_EQ(source->FrameCount().value(), 211);
  EXPECT_EQ(source->depth_convention(), DepthConvention::Millimetres());
  RgbdFrame frame;
  ASSERT_TRUE(source->Next(&frame));
  EXPECT_EQ(frame.timestamp_text, "0");

  GF_REQUIRE_DATASET(noisy, "icl_livingroom1_noisy5");
  FrameSourceOptions options;
  options.load_color = false;
  auto noisy_source = OpenFrameSource(noisy, options);  // picks depth_noisy/
  HoleStats stats;
  while (noisy_source->Next(&frame)) stats += CountHoles(frame.hole_mask);
  EXPECT_EQ(stats.pixels, 5u * 640 * 480);
  EXPECT_NEAR(stats.Fraction(), 0.127, 0.01);
  options.depth_folder = "depth_clean";
  auto clean_source = OpenFrameSource(noisy, options);
  HoleStats clean;
  while (clean_source->Next(&frame)) clean += CountHoles(frame.hole_mask);
  EXPECT_LT(clean.Fraction(), stats.Fraction());
}

TEST(KinectRawFolder, NyuFrameReadsAsRawDisparityRegisteredToColour) {
  GF_REQUIRE_DATASET(raw, "kinect_v1_raw");
  auto source = OpenFrameSource(raw, {});
  EXPECT_EQ(source->Kind(), "kinect_raw");
  EXPECT_EQ(source->depth_convention(), DepthConvention::KinectV1Raw11Bit());
  RgbdFrame frame;
  ASSERT_TRUE(source->Next(&frame));
  EXPECT_EQ(frame.color.size(), cv::Size(640, 480));
  // 7.2% of the sensor's pixels are 2047 (no return, some of it classed as projector shadow).
  EXPECT_NEAR(frame.sensor_holes.Fraction(), 0.0723, 0.0005);
  EXPECT_GT(frame.sensor_holes.shadow, 0u);
  // Registered depth covers most of the colour image at indoor depths.
  const double covered = cv::countNonZero(frame.depth > 0) / 307200.0;
  EXPECT_GT(covered, 0.6);
  EXPECT_FALSE(source->Next(&frame));
}

TEST(KinectRawFolder, FakenectRecordingPairsByTime) {
  testing::TempDir dir;
  // Two depth and two colour frames, plus an accelerometer dump the reader must ignore.
  std::ofstream(dir / "INDEX.txt") << "a-1294352291.200000-0.dump\n"
                                      "d-1294352291.235890-2213567.pgm\n"
                                      "r-1294352291.240000-2213600.ppm\n"
                                      "d-1294352291.269000-2215567.pgm\n"
                                      "r-1294352291.275000-2215600.ppm\n";
  const DepthConvention k = DepthConvention::KinectV1Raw11Bit();
  for (const char* name : {"d-1294352291.235890-2213567.pgm", "d-1294352291.269000-2215567.pgm"}) {
    // fakenect writes the raw little-endian buffer behind a P5 header.
    std::ofstream out(dir / name, std::ios::binary);
    out << "P5 640 480 65535\n";
    for (int i = 0; i < 640 * 480; ++i) {
      const uint16_t v = (i % 640) < 20 ? 2047 : k.FromMetres(2.0);
      out.put(static_cast<char>(v & 0xFF)).put(static_cast<char>(v >> 8));
    }
  }
  for (const char* name : {"r-1294352291.240000-2213600.ppm", "r-1294352291.275000-2215600.ppm"})
    cv::imwrite(dir / name, cv::Mat(480, 640, CV_8UC3, cv::Scalar(40, 80, 120)));
  auto source = OpenFrameSource(dir.path(), {});
  EXPECT_EQ(source->Kind(), "fakenect");
  EXPECT_EQ(source->FrameCount().value(), 2);
  RgbdFrame frame;
  ASSERT_TRUE(source->Next(&frame));
  EXPECT_EQ(frame.timestamp_text, "1294352291.235890");
  EXPECT_NEAR(frame.color_timestamp, 1294352291.24, 1e-6);
  EXPECT_NEAR(frame.sensor_holes.Fraction(), 20.0 / 640, 1e-9);
  // A plane 2 m in front of the IR camera; the nominal extrinsics turn it by 1 degree and move it
  // 1 cm, so in the colour camera it spans about 1.96-2.03 m.
  double lo, hi;
  cv::minMaxLoc(frame.depth, &lo, &hi, nullptr, nullptr, frame.depth > 0);
  EXPECT_GT(lo, 1.95);
  EXPECT_LT(hi, 2.05);
  EXPECT_NEAR(frame.depth.at<float>(240, 330), 1.99, 0.01);
  ASSERT_TRUE(source->Next(&frame));
  EXPECT_FALSE(source->Next(&frame));

  // A listed file that is missing is named in the error.
  std::ofstream(dir / "INDEX.txt", std::ios::app) << "d-1294352291.302000-2217567.pgm\n"
                                                     "r-1294352291.305000-2217600.ppm\n";
  auto broken = OpenFrameSource(dir.path(), {});
  ASSERT_TRUE(broken->Next(&frame));
  ASSERT_TRUE(broken->Next(&frame));
  try {
    broken->Next(&frame);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("d-1294352291.302000-2217567.pgm: file not found"),
              std::string::npos)
        << e.what();
  }
}

// A small TUM folder written here, for the failure cases.
class TinyTum : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::create_directories(dir_ / "rgb");
    fs::create_directories(dir_ / "depth");
    std::ofstream(dir_ / "camera.json")
        << R"({"width": 32, "height": 24, "fx": 40, "fy": 40, "cx": 15.5, "cy": 11.5,
               "distortion": [0,0,0,0,0], "depth_scale": 5000})";
    std::ofstream(dir_ / "rgb.txt") << "# color\n1.000 rgb/1.png\n2.000 rgb/2.png\n";
    std::ofstream(dir_ / "depth.txt") << "# depth\n1.005 depth/1.png\n2.010 depth/2.png\n";
    cv::imwrite(dir_ / "rgb/1.png", cv::Mat(24, 32, CV_8UC3, cv::Scalar(10, 20, 30)));
    cv::imwrite(dir_ / "rgb/2.png", cv::Mat(24, 32, CV_8UC3, cv::Scalar(10, 20, 30)));
    cv::imwrite(dir_ / "depth/1.png", cv::Mat(24, 32, CV_16UC1, cv::Scalar(5000)));
    cv::imwrite(dir_ / "depth/2.png", cv::Mat(24, 32, CV_16UC1, cv::Scalar(0)));
  }
  // Reads every frame; returns the error message or "".
  std::string ReadAll() {
    try {
      auto source = OpenFrameSource(dir_.path(), {});
      RgbdFrame f;
      while (source->Next(&f)) {
      }
      return "";
    } catch (const InputError& e) {
      return e.what();
    }
  }
  testing::TempDir dir_;
};

TEST_F(TinyTum, ReadsBothFrames) {
  EXPECT_EQ(ReadAll(), "");
  auto source = OpenFrameSource(dir_.path(), {});
  RgbdFrame f;
  ASSERT_TRUE(source->Next(&f));
  EXPECT_FLOAT_EQ(f.depth.at<float>(0, 0), 1.0f);
  ASSERT_TRUE(source->Next(&f));
  EXPECT_EQ(CountHoles(f.hole_mask).no_return, 32u * 24u);
  EXPECT_FALSE(source->Next(&f));
}

TEST_F(TinyTum, MissingIndexNamesTheFile) {
  fs::remove(dir_ / "depth.txt");
  try {
    OpenTumFolder(dir_.path(), {});
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(
        std::string(e.what()),
        (dir_ / "depth.txt") + ": file not found (a TUM folder needs both rgb.txt and depth.txt)");
  }
  // Nothing left that identifies the folder: the error names the input.
  fs::remove(dir_ / "rgb.txt");
  fs::remove_all(dir_ / "rgb");
  const std::string message = ReadAll();
  EXPECT_NE(message.find(dir_.path() + ": unrecognised input"), std::string::npos) << message;
}

// depth.txt without a usable rgb.txt is a broken TUM folder, not a Redwood folder (rgb/ and
// depth/ paired by position): the error names rgb.txt, whatever stands in its place.
TEST_F(TinyTum, DepthIndexWithoutAUsableColourIndexIsAnError) {
  const std::string rgb_txt = dir_ / "rgb.txt";
  auto expect = [&](const std::string& problem) {
    const std::string message = ReadAll();
    EXPECT_EQ(message,
              rgb_txt + ": " + problem + " (a TUM folder needs both rgb.txt and depth.txt)");
  };
  fs::remove(rgb_txt);
  expect("file not found");
  fs::create_directory(rgb_txt);
  expect("is a folder, not a file");
  fs::remove(rgb_txt);
  fs::create_symlink(dir_ / "no_such_index.txt", rgb_txt);
  expect("is a link to nothing");
  EXPECT_EQ(DetectInputKind(dir_.path()), "tum");
}

// A timestamp must be a finite number: std::stod reads "nan" and "inf", and one NaN used to drop
// frames from the association silently.
TEST_F(TinyTum, NonFiniteTimestampsNameTheFileAndLine) {
  for (const std::string bad : {"nan", "inf", "-inf", "NaN", "1.0x", "abc"}) {
    std::ofstream(dir_ / "depth.txt") << "# depth\n1.005 depth/1.png\n" << bad << " depth/2.png\n";
    EXPECT_EQ(ReadAll(), (dir_ / "depth.txt") + ": line 3: bad timestamp \"" + bad +
                             "\" (expected a finite number of seconds)");
  }
}

// The camera must describe the images: the first frame's headers are read when the folder opens,
// before anything is allocated for the camera's size.
TEST_F(TinyTum, ACameraThatDoesNotDescribeTheImagesIsRefusedAtOpen) {
  std::ofstream(dir_ / "camera.json", std::ios::trunc)
      << R"({"width": 4000, "height": 3000, "fx": 3500, "fy": 3500, "cx": 1999.5, "cy": 1499.5,
             "depth_scale": 5000})";
  try {
    OpenFrameSource(dir_.path(), {});
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              (dir_ / "depth/1.png") + ": depth image is 32x24 but the camera is 4000x3000");
  }
}

// Images under 32x24 are refused, naming the image.
TEST_F(TinyTum, ImagesBelowTheLeastSizeAreRefused) {
  cv::imwrite(dir_ / "depth/1.png", cv::Mat(1, 1, CV_16UC1, cv::Scalar(5000)));
  EXPECT_EQ(ReadAll(), (dir_ / "depth/1.png") +
                           ": depth image is 1x1, smaller than the least GlassFusion works on "
                           "(32x24)");
  cv::imwrite(dir_ / "depth/1.png", cv::Mat(24, 32, CV_16UC1, cv::Scalar(5000)));
  cv::imwrite(dir_ / "rgb/1.png", cv::Mat(24, 31, CV_8UC3, cv::Scalar(0)));
  EXPECT_EQ(ReadAll(), (dir_ / "rgb/1.png") +
                           ": colour image is 31x24, smaller than the least GlassFusion works on "
                           "(32x24)");
}

// Image sizes from the headers alone, as decoding finds them.
TEST(ReadImageSize, ReadsPngJpegAndNetpbmHeaders) {
  testing::TempDir dir;
  const cv::Mat color(37, 53, CV_8UC3, cv::Scalar(1, 2, 3));
  for (const char* name : {"a.png", "a.jpg", "a.ppm", "a.pgm"}) {
    const std::string path = dir / name;
    cv::Mat image = color;
    if (std::string(name) == "a.pgm") cv::cvtColor(color, image, cv::COLOR_BGR2GRAY);
    ASSERT_TRUE(cv::imwrite(path, image)) << name;
    const std::optional<cv::Size> size = ReadImageSize(path);
    ASSERT_TRUE(size.has_value()) << name;
    EXPECT_EQ(*size, cv::Size(53, 37)) << name;
  }
  ASSERT_TRUE(cv::imwrite(dir / "d.png", cv::Mat(480, 640, CV_16UC1, cv::Scalar(0))));
  EXPECT_EQ(ReadImageSize(dir / "d.png").value_or(cv::Size()), cv::Size(640, 480));
  std::ofstream(dir / "junk.png") << "not an image";
  EXPECT_FALSE(ReadImageSize(dir / "junk.png").has_value());
  EXPECT_FALSE(ReadImageSize(dir / "missing.png").has_value());
}

TEST_F(TinyTum, CorruptColourImageNamesTheFile) {
  std::ofstream(dir_ / "rgb/2.png", std::ios::trunc) << "not a png";
  const std::string message = ReadAll();
  EXPECT_NE(message.find("rgb/2.png: cannot decode"), std::string::npos) << message;
}

TEST_F(TinyTum, MismatchedSizesAndBitDepthAreReported) {
  cv::imwrite(dir_ / "depth/2.png", cv::Mat(12, 16, CV_16UC1, cv::Scalar(0)));
  EXPECT_NE(ReadAll().find("depth/2.png: depth image is 16x12 but the camera is 32x24"),
            std::string::npos);
  cv::imwrite(dir_ / "depth/2.png", cv::Mat(24, 32, CV_8UC1, cv::Scalar(0)));
  EXPECT_NE(ReadAll().find("depth/2.png: depth image is 8-bit, expected 16-bit"),
            std::string::npos);
  cv::imwrite(dir_ / "depth/2.png", cv::Mat(24, 32, CV_16UC1, cv::Scalar(0)));
  cv::imwrite(dir_ / "rgb/2.png", cv::Mat(23, 32, CV_8UC3, cv::Scalar(0)));
  EXPECT_NE(ReadAll().find("rgb/2.png: colour image is 32x23"), std::string::npos) << ReadAll();
}

TEST(InMemoryFrameSource, DeliversFramesInOrder) {
  std::vector<RgbdFrame> frames(3);
  for (int i = 0; i < 3; ++i) frames[i].index = i;
  InMemoryFrameSource source(CameraFile{}, frames);
  EXPECT_EQ(source.FrameCount().value(), 3);
  RgbdFrame f;
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(source.Next(&f));
    EXPECT_EQ(f.index, i);
  }
  EXPECT_FALSE(source.Next(&f));
}

}  // namespace
}  // namespace gf
