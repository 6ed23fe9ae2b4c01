// RealSense .bag input: bags written here with the same library, in librealsense's layout (topic
// names, CameraInfo, tf, the Depth Units option, the float librealsense 2.49+ appends to images),
// read back as frames whose depth is registered to colour.
#include "acquisition/realsense_bag.h"

#include <geometry_msgs/Transform.h>
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Float32.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "acquisition/errors.h"
#include "tests/testing.h"

// sensor_msgs/Image as librealsense 2.49 and later writes it: the standard fields, then a float32
// (the depth units; 0 on colour frames).
namespace gf_test {
struct RsImage {
  sensor_msgs::Image image;
  float depth_units = 0.f;
};
}  // namespace gf_test

namespace ros {
namespace message_traits {
template <>
struct MD5Sum<gf_test::RsImage> {
  static const char* value() { return MD5Sum<sensor_msgs::Image>::value(); }
  static const char* value(const gf_test::RsImage&) { return value(); }
};
template <>
struct DataType<gf_test::RsImage> {
  static const char* value() { return "sensor_msgs/Image"; }
  static const char* value(const gf_test::RsImage&) { return value(); }
};
template <>
struct Definition<gf_test::RsImage> {
  static const char* value() { return Definition<sensor_msgs::Image>::value(); }
  static const char* value(const gf_test::RsImage&) { return value(); }
};
}  // namespace message_traits
namespace serialization {
template <>
struct Serializer<gf_test::RsImage> {
  template <typename Stream, typename T>
  inline static void allInOne(Stream& stream, T m) {
    stream.next(m.image);
    stream.next(m.depth_units);
  }
  ROS_DECLARE_ALLINONE_SERIALIZER
};
}  // namespace serialization
}  // namespace ros

namespace gf {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 5;
constexpr double kPlaneZ = 1.5;          // the scene: a wall 1.5 m in front of the depth camera
constexpr double kBaselineM = 0.015;     // colour camera 15 mm along the depth camera's x
const ros::Time kStart(1000, 0);         // the device clock at the first frame

struct BagSpec {
  uint32_t compression = rosbag::compression::LZ4;
  bool units_option = true;        // the Depth_Units option topic (else only the trailing float)
  float depth_units = 0.001f;      // metres per unit
  int depth_streams = 1;           // a second Depth_1 stream when 2
  std::string color_encoding = "rgb8";
};

sensor_msgs::CameraInfo Info(int width, int height, double f, const std::string& model) {
  sensor_msgs::CameraInfo info;
  info.width = width, info.height = height;
  info.K = {f, 0, width / 2.0, 0, f, height / 2.0, 0, 0, 1};
  info.distortion_model = model;
  info.D = {0, 0, 0, 0, 0};
  return info;
}

// Colour pixel (u, v): a pattern with distinct channels.
cv::Vec3b Rgb(int u, int v) { return cv::Vec3b(3 * u, 2 * v, 200); }

void WriteBag(const std::string& path, const BagSpec& spec) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  bag.setCompression(static_cast<rosbag::compression::CompressionType>(spec.compression));
  const ros::Time first(0, 1);  // librealsense writes static records at the bag's first instant
  const std::string depth = "/device_0/sensor_0/Depth_0", color = "/device_0/sensor_1/Color_0";
  bag.write(depth + "/info/camera_info", first, Info(64, 48, 50, "Brown Conrady"));
  bag.write(color + "/info/camera_info", first, Info(80, 60, 62, "Inverse Brown Conrady"));
  geometry_msgs::Transform identity, depth_to_color;
  identity.rotation.w = depth_to_color.rotation.w = 1;
  depth_to_color.translation.x = -kBaselineM;  // p_color = p_depth + t: colour sits at +x
  bag.write(depth + "/tf/0", first, identity);
  if (spec.depth_streams > 1) {
    bag.write("/device_0/sensor_0/Depth_1/info/camera_info", first,
              Info(64, 48, 50, "Brown Conrady"));
    bag.write("/device_0/sensor_0/Depth_1/tf/0", first, identity);
  }
  bag.write(color + "/tf/0", first, depth_to_color);
  if (spec.units_option) {
    std_msgs::Float32 units;
    units.data = spec.depth_units;
    bag.write("/device_0/sensor_0/option/Depth_Units/value", first, units);
  }
  for (int k = 0; k < kFrames; ++k) {
    const ros::Time t = kStart + ros::Duration(k / 30.0);
    gf_test::RsImage d;
    d.image.header.stamp = t;
    d.image.header.frame_id = "1";
    d.image.width = 64, d.image.height = 48, d.image.encoding = "mono16", d.image.step = 128;
    d.image.data.resize(128 * 48);
    const uint16_t raw = static_cast<uint16_t>(std::lround(kPlaneZ / spec.depth_units));
    for (size_t i = 0; i < d.image.data.size(); i += 2) std::memcpy(&d.image.data[i], &raw, 2);
    d.depth_units = spec.depth_units;
    const ros::Time arrival = ros::Time(1, 0) + ros::Duration(k / 30.0);
    bag.write(depth + "/image/data", arrival, d);
    if (spec.depth_streams > 1) bag.write("/device_0/sensor_0/Depth_1/image/data", arrival, d);
    gf_test::RsImage c;
    c.image.header.stamp = t + ros::Duration(0.003);  // colour 3 ms after depth
    c.image.header.frame_id = "1";
    c.image.width = 80, c.image.height = 60, c.image.encoding = spec.color_encoding;
    c.image.step = 240;
    c.image.data.resize(240 * 60);
    for (int v = 0; v < 60; ++v)
      for (int u = 0; u < 80; ++u)
        for (int ch = 0; ch < 3; ++ch) c.image.data[v * 240 + u * 3 + ch] = Rgb(u, v)[ch];
    bag.write(color + "/image/data", arrival + ros::Duration(0.005), c);
  }
  bag.close();
}

std::vector<RgbdFrame> ReadAll(FrameSource* source) {
  std::vector<RgbdFrame> frames;
  RgbdFrame f;
  while (source->Next(&f)) frames.push_back(f);
  return frames;
}

TEST(RealSenseBag, ReadsFramesRegisteredToColourWithTheBagsCalibration) {
  if (!RealSenseBagSupported()) GTEST_SKIP() << "built without librosbag-storage-dev";
  testing::TempDir dir;
  for (uint32_t compression : {rosbag::compression::LZ4, rosbag::compression::BZ2}) {
    const std::string path = dir / ("cap" + std::to_string(compression) + ".bag");
    BagSpec spec;
    spec.compression = compression;
    WriteBag(path, spec);
    ASSERT_EQ(DetectInputKind(path), "realsense_bag");
    auto source = OpenFrameSource(path, {});
    EXPECT_EQ(source->Kind(), "realsense_bag");
    ASSERT_EQ(source->FrameCount(), kFrames);
    const CameraFile& cf = source->camera_file();
    EXPECT_EQ(cf.camera.width, 80);
    EXPECT_DOUBLE_EQ(cf.camera.fx, 62);
    ASSERT_TRUE(cf.depth_camera.has_value());
    EXPECT_DOUBLE_EQ(cf.depth_camera->fx, 50);
    EXPECT_FALSE(cf.depth_registered_to_color);
    EXPECT_NEAR(cf.color_from_depth.translation().x(), -kBaselineM, 1e-9);
    EXPECT_DOUBLE_EQ(cf.depth_scale, 1000);
    const std::vector<RgbdFrame> frames = ReadAll(source.get());
    ASSERT_EQ(frames.size(), static_cast<size_t>(kFrames));
    for (int k = 0; k < kFrames; ++k) {
      const RgbdFrame& f = frames[k];
      EXPECT_NEAR(f.timestamp, 1000 + k / 30.0, 1e-6);
      EXPECT_NEAR(f.color_timestamp - f.timestamp, 0.003, 1e-6);
      ASSERT_EQ(f.depth.size(), cv::Size(80, 60));  // registered to the colour camera
      // The wall seen from the colour camera: 1.5 m where the depth camera saw it (its narrower
      // view leaves the colour image's border empty).
      int on_wall = 0;
      for (int v = 0; v < 60; ++v)
        for (int u = 0; u < 80; ++u) {
          const float z = f.depth.at<float>(v, u);
          if (z > 0) {
            EXPECT_NEAR(z, kPlaneZ, 0.002) << u << "," << v;
          }
          on_wall += z > 0;
        }
      EXPECT_GT(on_wall, 80 * 60 / 2);
      const cv::Vec3b rgb = Rgb(10, 20);
      EXPECT_EQ(f.color.at<cv::Vec3b>(20, 10), cv::Vec3b(rgb[2], rgb[1], rgb[0]));  // BGR
    }
  }
}

TEST(RealSenseBag, DepthUnitsFromTheFloatNewerRecordersAppendToEachImage) {
  if (!RealSenseBagSupported()) GTEST_SKIP() << "built without librosbag-storage-dev";
  testing::TempDir dir;
  BagSpec spec;
  spec.units_option = false;
  spec.depth_units = 0.0001f;  // 0.1 mm units (a D405)
  WriteBag(dir / "d405.bag", spec);
  auto source = OpenFrameSource(dir / "d405.bag", {});
  EXPECT_DOUBLE_EQ(source->camera_file().depth_scale, 10000);
  RgbdFrame f;
  ASSERT_TRUE(source->Next(&f));
  EXPECT_NEAR(f.depth.at<float>(30, 40), kPlaneZ, 0.002);
}

TEST(RealSenseBag, SeveralDepthStreamsNeedATopic) {
  if (!RealSenseBagSupported()) GTEST_SKIP() << "built without librosbag-storage-dev";
  testing::TempDir dir;
  BagSpec spec;
  spec.depth_streams = 2;
  WriteBag(dir / "two.bag", spec);
  try {
    OpenFrameSource(dir / "two.bag", {});
    ADD_FAILURE() << "opened a bag with two depth streams without a topic";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--depth-topic"), std::string::npos) << e.what();
  }
  FrameSourceOptions options;
  options.bag_depth_topic = "/device_0/sensor_0/Depth_1/image/data";
  EXPECT_EQ(OpenFrameSource(dir / "two.bag", options)->FrameCount(), kFrames);
  options.bag_depth_topic = "/no/such/image/data";
  EXPECT_THROW(OpenFrameSource(dir / "two.bag", options), InputError);
}

TEST(RealSenseBag, TruncatedCorruptAndForeignFilesAreInputErrorsNamingTheFile) {
  if (!RealSenseBagSupported()) GTEST_SKIP() << "built without librosbag-storage-dev";
  testing::TempDir dir;
  const std::string whole = dir / "whole.bag";
  WriteBag(whole, {});
  std::ifstream in(whole, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto write = [&](const std::string& name, const std::string& content) {
    std::ofstream(dir / name, std::ios::binary) << content;
    return dir / name;
  };
  const std::string truncated = write("truncated.bag", bytes.substr(0, bytes.size() / 2));
  const std::string text = write("text.bag", "not a bag\n");
  std::string flipped = bytes;  // a chunk's compressed bytes overwritten
  for (size_t i = bytes.size() / 3; i < bytes.size() / 3 + 64; ++i) flipped[i] = '\x5a';
  const std::string corrupt = write("corrupt.bag", flipped);
  for (const std::string& path : {truncated, text, corrupt}) {
    try {
      auto source = OpenFrameSource(path, {});
      RgbdFrame f;
      while (source->Next(&f)) {
      }
      // Overwritten pixels of an uncompressed chunk cannot be told from real ones; LZ4's can.
      ADD_FAILURE() << path << " read without an error";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(path, 0), 0u) << e.what();
    }
  }
}

TEST(RealSenseBag, AnUnsupportedColourEncodingIsRefusedNamingIt) {
  if (!RealSenseBagSupported()) GTEST_SKIP() << "built without librosbag-storage-dev";
  testing::TempDir dir;
  BagSpec spec;
  spec.color_encoding = "bayer_rggb8";
  WriteBag(dir / "bayer.bag", spec);
  auto source = OpenFrameSource(dir / "bayer.bag", {});
  RgbdFrame f;
  try {
    source->Next(&f);
    ADD_FAILURE() << "read a Bayer colour image";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bayer_rggb8"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace gf
