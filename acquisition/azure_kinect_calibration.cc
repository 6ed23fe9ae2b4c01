// The Azure Kinect's calibration.json and camera modes (acquisition/azure_kinect_mkv.h), after the
// SDK's src/calibration/calibration.c and src/transformation/mode_specific_calibration.c.
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "acquisition/azure_kinect_mkv.h"
#include "acquisition/errors.h"

namespace gf {

std::optional<AzureKinectMode> AzureKinectDepthMode(const std::string& name) {
  // The depth sensor is 1024x1024; the narrow modes crop a 640x576 window that is not centred.
  if (name == "NFOV_UNBINNED") return AzureKinectMode{1024, 1024, 192, 180, 640, 576};
  if (name == "NFOV_2X2BINNED") return AzureKinectMode{512, 512, 96, 90, 320, 288};
  if (name == "WFOV_UNBINNED" || name == "PASSIVE_IR")
    return AzureKinectMode{1024, 1024, 0, 0, 1024, 1024};
  if (name == "WFOV_2X2BINNED") return AzureKinectMode{512, 512, 0, 0, 512, 512};
  return std::nullopt;
}

std::optional<AzureKinectMode> AzureKinectColorMode(int height) {
  // The colour sensor is 4:3 (4096x3072); the 16:9 modes crop rows at the top and bottom.
  switch (height) {
    case 720: return AzureKinectMode{1280, 960, 0, 120, 1280, 720};
    case 1080: return AzureKinectMode{1920, 1440, 0, 180, 1920, 1080};
    case 1440: return AzureKinectMode{2560, 1920, 0, 240, 2560, 1440};
    case 1536: return AzureKinectMode{2048, 1536, 0, 0, 2048, 1536};
    case 2160: return AzureKinectMode{3840, 2880, 0, 360, 3840, 2160};
    case 3072: return AzureKinectMode{4096, 3072, 0, 0, 4096, 3072};
    default: return std::nullopt;
  }
}

namespace {

constexpr const char* kDepthLocation = "CALIBRATION_CameraLocationD0";
constexpr const char* kColorLocation = "CALIBRATION_CameraLocationPV0";
constexpr const char* kBrownConrady = "CALIBRATION_LensDistortionModelBrownConrady";

struct SensorCamera {
  Camera camera;
  // Rt: takes points from the device's frame (the depth camera's) into this camera's (metres).
  Eigen::Matrix3d rotation;
  Eigen::Vector3d translation;
};

// One camera of the calibration, made for its mode. ModelParameters: cx, cy, fx, fy normalised
// to the sensor, k1-k6, the centre of distortion (codx, cody), then p2 and p1 (that order).
SensorCamera ParseCamera(const nlohmann::json& cameras, const char* location,
                         const AzureKinectMode& mode, const std::string& where) {
  for (const nlohmann::json& c : cameras) {
    if (c.value("Location", "") != location) continue;
    const nlohmann::json& intrinsics = c.at("Intrinsics");
    const std::string model = intrinsics.value("ModelType", "");
    if (model != kBrownConrady)
      throw InputError(where, std::string(location) + ": lens model \"" + model +
                                  "\" is not supported (" + kBrownConrady + " is)");
    std::vector<double> p = intrinsics.at("ModelParameters").get<std::vector<double>>();
    if (p.size() < 14)
      throw InputError(where, std::string(location) + ": " + std::to_string(p.size()) +
                                  " ModelParameters, expected 14");
    if (p[10] != 0 || p[11] != 0)
      throw InputError(where, std::string(location) +
                                  ": a centre of distortion off the principal point (codx, cody) "
                                  "is not in OpenCV's lens model");
    const int sensor_w = c.at("SensorWidth"), sensor_h = c.at("SensorHeight");
    if (sensor_w * 9 / 16 == sensor_h) {  // an early 16:9 colour calibration: make it 4:3
      p[1] = (p[1] * 2304 + 384) / 3072.0;
      p[3] = p[3] * 2304 / 3072.0;
    }
    SensorCamera s;
    Camera& k = s.camera;
    k.width = mode.width;
    k.height = mode.height;
    k.cx = p[0] * mode.binned_width - mode.crop_x - 0.5;  // the SDK's pixel centres are at +0.5
    k.cy = p[1] * mode.binned_height - mode.crop_y - 0.5;
    k.fx = p[2] * mode.binned_width;
    k.fy = p[3] * mode.binned_height;
    k.distortion = {p[4], p[5], p[13], p[12], p[6], p[7], p[8], p[9]};
    const std::vector<double> r = c.at("Rt").at("Rotation").get<std::vector<double>>();
    const std::vector<double> t = c.at("Rt").at("Translation").get<std::vector<double>>();
    if (r.size() != 9 || t.size() != 3)
      throw InputError(where, std::string(location) + ": Rt needs 9 rotation and 3 translation "
                                                      "values");
    s.rotation = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(r.data());
    s.translation = Eigen::Vector3d(t[0], t[1], t[2]);
    std::string problem;
    if (!k.CheckPlausible(&problem))
      throw InputError(where, std::string(location) + ": " + problem);
    return s;
  }
  throw InputError(where, std::string("calibration.json has no camera ") + location);
}

}  // namespace

CameraFile AzureKinectCalibration(const std::string& json_text, const std::string& depth_mode,
                                  int color_height, const std::string& where) {
  const std::optional<AzureKinectMode> depth = AzureKinectDepthMode(depth_mode);
  if (!depth) throw InputError(where, "unknown depth mode \"" + depth_mode + "\"");
  if (depth_mode.rfind("WFOV", 0) == 0 || depth_mode == "PASSIVE_IR")
    throw InputError(where, "depth mode " + depth_mode +
                                " is not supported (its image's corners lie outside the lens "
                                "model; NFOV_UNBINNED and NFOV_2X2BINNED are read)");
  const std::optional<AzureKinectMode> color = AzureKinectColorMode(color_height);
  if (!color) throw InputError(where, "unknown colour mode of " + std::to_string(color_height) +
                                          " rows");
  CameraFile file;
  try {
    const nlohmann::json j = nlohmann::json::parse(json_text);
    const nlohmann::json& cameras = j.at("CalibrationInformation").at("Cameras");
    const SensorCamera d = ParseCamera(cameras, kDepthLocation, *depth, where);
    const SensorCamera c = ParseCamera(cameras, kColorLocation, *color, where);
    // Each Rt takes points from the device's frame (the depth camera's) into its camera's.
    const Eigen::Matrix3d rotation = c.rotation * d.rotation.transpose();
    Eigen::Quaterniond q(rotation);
    q.normalize();
    file.camera = c.camera;
    file.depth_camera = d.camera;
    file.color_from_depth = SE3(q, c.translation - rotation * d.translation);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(where, std::string("calibration.json: ") + e.what());
  }
  file.depth_registered_to_color = false;
  file.depth_scale = 1000.0;     // millimetres
  file.depth_readout_s = 0.0;    // time of flight: every pixel of a frame at once
  return file;
}

std::string AzureKinectCalibrationJson(const Camera& depth_camera, const std::string& depth_mode,
                                       const Camera& color_camera, int color_height,
                                       const SE3& color_from_depth) {
  auto camera = [](const Camera& k, const AzureKinectMode& mode, const char* location,
                   const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) {
    const auto& d = k.distortion;
    const std::vector<double> p = {(k.cx + 0.5 + mode.crop_x) / mode.binned_width,
                                   (k.cy + 0.5 + mode.crop_y) / mode.binned_height,
                                   k.fx / mode.binned_width,
                                   k.fy / mode.binned_height,
                                   d[0], d[1], d[4], d[5], d[6], d[7], 0, 0, d[3], d[2]};
    const bool depth = std::string(location) == kDepthLocation;
    nlohmann::ordered_json j;
    j["Intrinsics"] = {{"ModelParameterCount", 14}, {"ModelParameters", p},
                       {"ModelType", kBrownConrady}};
    j["Location"] = location;
    j["Purpose"] = depth ? "CALIBRATION_CameraPurposeDepth" : "CALIBRATION_CameraPurposePhotoVideo";
    j["MetricRadius"] = depth ? 1.74 : 0.0;
    std::vector<double> r(9);
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(r.data()) = rotation;
    j["Rt"] = {{"Rotation", r}, {"Translation", {translation.x(), translation.y(), translation.z()}}};
    j["SensorHeight"] = depth ? 1024 : 3072;
    j["SensorWidth"] = depth ? 1024 : 4096;
    return j;
  };
  const AzureKinectMode depth = AzureKinectDepthMode(depth_mode).value();
  const AzureKinectMode color = AzureKinectColorMode(color_height).value();
  nlohmann::ordered_json j;
  j["CalibrationInformation"]["Cameras"] = {
      camera(depth_camera, depth, kDepthLocation, Eigen::Matrix3d::Identity(),
             Eigen::Vector3d::Zero()),
      camera(color_camera, color, kColorLocation, color_from_depth.RotationMatrix(),
             color_from_depth.translation())};
  return j.dump(1);
}

}  // namespace gf
