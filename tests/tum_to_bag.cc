// Test tool: writes a TUM folder's frames as a RealSense recording (.bag in librealsense's layout,
// LZ4 chunks), so that the same frames can be read both ways. Depth is written as it is in the
// folder (aligned to colour: both streams get the colour camera's intrinsics and an identity
// extrinsic) with Depth_Units = 1 / camera.json's depth_scale; colour as rgb8; each image's
// header stamp is its index timestamp.
// usage: gf_tum_to_bag FOLDER OUT.bag [FRAMES]
#include <geometry_msgs/Transform.h>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Float32.h>

#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "acquisition/camera.h"
#include "acquisition/frame_source.h"
#include "acquisition/tum_index.h"

namespace {

sensor_msgs::Image ToMessage(const cv::Mat& image, const std::string& encoding, double stamp) {
  sensor_msgs::Image m;
  m.header.stamp = ros::Time(stamp);
  m.width = image.cols, m.height = image.rows, m.encoding = encoding;
  m.step = static_cast<uint32_t>(image.cols * image.elemSize());
  m.data.resize(static_cast<size_t>(m.step) * image.rows);
  for (int v = 0; v < image.rows; ++v)
    std::memcpy(&m.data[static_cast<size_t>(v) * m.step], image.ptr(v), m.step);
  return m;
}

int Convert(const std::string& folder, const std::string& out, size_t frames) {
  const gf::CameraFile cf = gf::LoadCameraFile(folder + "/camera.json");
  sensor_msgs::CameraInfo info;
  info.width = cf.camera.width, info.height = cf.camera.height;
  info.K = {cf.camera.fx, 0, cf.camera.cx, 0, cf.camera.fy, cf.camera.cy, 0, 0, 1};
  info.distortion_model = "Brown Conrady";
  info.D = cf.camera.DistortionCoefficients();
  rosbag::Bag bag(out, rosbag::bagmode::Write);
  bag.setCompression(rosbag::compression::LZ4);
  const ros::Time first(0, 1);
  const std::string depth = "/device_0/sensor_0/Depth_0", color = "/device_0/sensor_1/Color_0";
  geometry_msgs::Transform identity;
  identity.rotation.w = 1;
  for (const std::string& stream : {depth, color}) {
    bag.write(stream + "/info/camera_info", first, info);
    bag.write(stream + "/tf/0", first, identity);
  }
  std_msgs::Float32 units;
  units.data = static_cast<float>(1.0 / cf.depth_scale);
  bag.write("/device_0/sensor_0/option/Depth_Units/value", first, units);
  const auto depth_lines = gf::ReadTumIndex(folder, "depth.txt");
  const auto color_lines = gf::ReadTumIndex(folder, "rgb.txt");
  std::vector<double> td, tc;
  for (const auto& l : depth_lines) td.push_back(l.timestamp);
  for (const auto& l : color_lines) tc.push_back(l.timestamp);
  const double t0 = std::min(td.front(), tc.front());
  size_t written = 0;
  for (const auto& [i, j] : gf::AssociateTimestamps(td, tc, 0.02)) {
    if (written++ == frames) break;
    const cv::Mat d = cv::imread(depth_lines[i].path, cv::IMREAD_UNCHANGED);
    cv::Mat rgb = cv::imread(color_lines[j].path, cv::IMREAD_COLOR);
    if (d.type() != CV_16UC1 || rgb.empty()) {
      std::fprintf(stderr, "%s: unreadable frame %zu\n", folder.c_str(), i);
      return 2;
    }
    cv::cvtColor(rgb, rgb, cv::COLOR_BGR2RGB);
    // Bag time: the recorder's clock from the first frame, as librealsense writes it.
    bag.write(depth + "/image/data", ros::Time(1 + td[i] - t0),
              ToMessage(d, "mono16", depth_lines[i].timestamp));
    bag.write(color + "/image/data", ros::Time(1 + tc[j] - t0),
              ToMessage(rgb, "rgb8", color_lines[j].timestamp));
  }
  bag.close();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: gf_tum_to_bag FOLDER OUT.bag [FRAMES]\n");
    return 2;
  }
  try {
    return Convert(argv[1], argv[2], argc > 3 ? std::stoul(argv[3]) : size_t(-1));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
}
