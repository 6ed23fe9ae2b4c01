// Pinhole camera with OpenCV's (Brown-Conrady, rational) distortion, and the camera.json format.
//
// Units: focal lengths and principal point in pixels, image size in pixels, points in metres.
// Pixel convention: (0,0) is the centre of the top-left pixel (OpenCV, TUM, ICL-NUIM).
// Frames: a point_in_camera has +x right, +y down, +z forward (optical axis).
//
// camera.json (schema of ../shared/datasets/README.md):
//   { "width": 640, "height": 480, "fx": 525.0, "fy": 525.0, "cx": 319.5, "cy": 239.5,
//     "distortion": [k1, k2, p1, p2, k3], "depth_scale": 5000.0,
//     "depth_registered_to_color": true }
// "distortion" holds up to 8 coefficients, OpenCV's order [k1, k2, p1, p2, k3, k4, k5, k6] (k4-k6:
// the rational model's denominator, as the Azure Kinect's lenses need); missing ones are zero.
// depth_scale is raw depth units per metre (PNG value / depth_scale = metres).
// Sources whose depth is not registered to colour (raw Kinect v1 disparity, some OpenNI devices)
// add the depth (IR) camera and the rigid transform between the two:
//     "depth_registered_to_color": false,
//     "depth_camera": { "width": 640, "height": 480, "fx": ..., "fy": ..., "cx": ..., "cy": ...,
//                       "distortion": [...] },
//     "color_from_depth": { "rotation": [r00, r01, ..., r22], "translation": [tx, ty, tz] }
// (rotation row-major; point_in_color = R * point_in_depth + t, metres).
//
// Usage:
//   gf::CameraFile file = gf::LoadCameraFile("tum/camera.json");
//   Eigen::Vector2d uv = file.camera.Project(point_in_camera);
//   Eigen::Vector3d p = file.camera.BackProject(uv, depth_m);
//
// Thread-safety: Camera is a value type; const methods are safe to call concurrently.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/se3.h"

namespace gf {

// The field of view a camera may have across its image, degrees, each way: from a long lens's to
// a fisheye's (beyond 170 degrees the pinhole and Brown-Conrady models no longer hold).
inline constexpr double kMinFieldOfViewDeg = 20;
inline constexpr double kMaxFieldOfViewDeg = 170;

// OpenCV's lens model (cv::projectPoints with 8 coefficients) in the caller's scalar type, for
// loops that project many points in float. On normalised coordinates (x/z, y/z), r^2 = x^2 + y^2:
//   radial = (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6)
//   x_d = x radial + 2 p1 x y + p2 (r^2 + 2 x^2),  y_d = y radial + p1 (r^2 + 2 y^2) + 2 p2 x y.
// With k4 = k5 = k6 = 0 the denominator is exactly 1 and this is the 5-coefficient model.
template <typename T>
struct LensModel {
  explicit LensModel(const std::array<double, 8>& d)
      : k1(T(d[0])), k2(T(d[1])), p1(T(d[2])), p2(T(d[3])), k3(T(d[4])), k4(T(d[5])),
        k5(T(d[6])), k6(T(d[7])) {}
  T Radial(T r2) const {
    return (T(1) + r2 * (k1 + r2 * (k2 + r2 * k3))) / (T(1) + r2 * (k4 + r2 * (k5 + r2 * k6)));
  }
  T TangentialX(T x, T y, T r2) const { return T(2) * p1 * x * y + p2 * (r2 + T(2) * x * x); }
  T TangentialY(T x, T y, T r2) const { return p1 * (r2 + T(2) * y * y) + T(2) * p2 * x * y; }
  void Distort(T x, T y, T* x_d, T* y_d) const {
    const T r2 = x * x + y * y, radial = Radial(r2);
    *x_d = x * radial + T(2) * p1 * x * y + p2 * (r2 + T(2) * x * x);
    *y_d = y * radial + p1 * (r2 + T(2) * y * y) + T(2) * p2 * x * y;
  }
  T k1, k2, p1, p2, k3, k4, k5, k6;
};

struct Camera {
  int width = 640;    // image width, pixels
  int height = 480;   // image height, pixels
  double fx = 525.0;  // focal length along x, pixels
  double fy = 525.0;  // focal length along y, pixels
  double cx = 319.5;  // principal point x, pixels
  double cy = 239.5;  // principal point y, pixels
  // OpenCV distortion [k1, k2, p1, p2, k3, k4, k5, k6] (LensModel), dimensionless; all zero =
  // ideal pinhole.
  std::array<double, 8> distortion{0, 0, 0, 0, 0, 0, 0, 0};

  // Valid intrinsics: positive size and focal lengths, finite values. Message says what is wrong.
  bool Check(std::string* message = nullptr) const;
  // Valid intrinsics (Check) that a real camera could have; LoadCameraFile refuses others, and the
  // message names the field:
  //  - a size from kMinImageWidthPx x kMinImageHeightPx to kMaxImageSidePx (acquisition/bounds.h);
  //  - the principal point inside the image;
  //  - a field of view of kMinFieldOfViewDeg to kMaxFieldOfViewDeg across the image each way
  //    (RGB-D sensors see 45-90 degrees; fx = 1e30 would see nothing, fx = 1 everything);
  //  - a radial distortion r_d(r) = r radial(r^2) (LensModel) that grows with the undistorted
  //    normalised radius r until it reaches the image's corners, so that every pixel has one ray
  //    (the tangential terms are small and not tested).
  bool CheckPlausible(std::string* message = nullptr) const;
  bool HasDistortion() const;
  // The coefficients as camera.json, COLMAP and ROS write them: 5 (k1, k2, p1, p2, k3) when
  // k4 = k5 = k6 = 0, else all 8.
  std::vector<double> DistortionCoefficients() const;

  // Ideal pinhole projection (no distortion). point_in_camera.z() must be > 0.
  Eigen::Vector2d Project(const Eigen::Vector3d& point_in_camera) const;
  // Inverse of Project for a pixel and its depth along the optical axis (metres, z not range).
  Eigen::Vector3d BackProject(const Eigen::Vector2d& pixel, double depth) const;

  // Distorted projection, the same model as cv::projectPoints.
  Eigen::Vector2d ProjectDistorted(const Eigen::Vector3d& point_in_camera) const;
  // Normalised image coordinates (x/z, y/z) <-> distorted normalised coordinates.
  Eigen::Vector2d Distort(const Eigen::Vector2d& normalized) const;
  // Iterative inverse of Distort (fixed-point, as cv::undistortPoints); exact to ~1e-9 for
  // Kinect-like lenses.
  Eigen::Vector2d Undistort(const Eigen::Vector2d& distorted_normalized) const;
  // Undistorted normalised coordinates (x/z, y/z) of the ray through a (distorted) image pixel.
  Eigen::Vector2d UndistortPixel(const Eigen::Vector2d& pixel) const {
    return Undistort({(pixel.x() - cx) / fx, (pixel.y() - cy) / fy});
  }

  bool InImage(const Eigen::Vector2d& pixel) const {
    return pixel.x() >= -0.5 && pixel.y() >= -0.5 && pixel.x() < width - 0.5 &&
           pixel.y() < height - 0.5;
  }

  Eigen::Matrix3d K() const;
  cv::Mat CvK() const;           // 3x3 CV_64F
  cv::Mat CvDistortion() const;  // 1x8 CV_64F
  // cv::remap maps (fixed point, the fast kind) that undistort this camera's images onto the
  // ideal pinhole camera K with the same size. Computed once per camera and shared between calls:
  // read them, never write into them.
  void UndistortionMaps(cv::Mat* map1, cv::Mat* map2) const;
  // The same intrinsics, size and distortion.
  bool operator==(const Camera& other) const;
  // The same camera for an image scaled by `factor` (e.g. 0.5 for a pyramid level).
  Camera Scaled(double factor) const;
};

// Where each (distorted) pixel of a camera lies in the undistorted pinhole image: exact
// (Camera::UndistortPixel) on a grid of every 8th pixel, bilinear in between. The distortion field
// is smooth, so the interpolation is far below a pixel off, at a 64th of the cost of undistorting
// every pixel. Without distortion, At() is the pixel itself. Immutable after construction; the
// grid is built once per camera and shared by every object made for it (the fill makes several
// per pair, and the iterative undistortion of ~5,000 nodes takes about a millisecond).
class UndistortedPixels {
 public:
  explicit UndistortedPixels(const Camera& camera);
  // Undistorted pinhole pixel of pixel (x, y), which must lie in the image.
  Eigen::Vector2d At(int x, int y) const {
    if (!distorted_) return Eigen::Vector2d(x, y);
    const int i = std::min(x / kStep, nodes_x_ - 2), j = std::min(y / kStep, nodes_y_ - 2);
    const double a = (x - i * kStep) / static_cast<double>(kStep),
                 b = (y - j * kStep) / static_cast<double>(kStep);
    const Eigen::Vector2d* n = &(*nodes_)[j * nodes_x_ + i];
    return (1 - b) * ((1 - a) * n[0] + a * n[1]) +
           b * ((1 - a) * n[nodes_x_] + a * n[nodes_x_ + 1]);
  }
  // Normalised coordinates (x/z, y/z) of the ray through pixel (x, y), as Camera::UndistortPixel.
  Eigen::Vector2d Ray(int x, int y) const {
    const Eigen::Vector2d u = At(x, y);
    return {(u.x() - camera_.cx) / camera_.fx, (u.y() - camera_.cy) / camera_.fy};
  }

 private:
  static constexpr int kStep = 8;
  Camera camera_;
  bool distorted_;
  int nodes_x_ = 0, nodes_y_ = 0;
  std::shared_ptr<const std::vector<Eigen::Vector2d>> nodes_;
};

// The order in which a depth sensor exposes its image's lines (camera.json's
// depth_readout_order; registration/rolling_shutter.h).
enum class ReadoutOrder { kTopToBottom, kBottomToTop, kLeftToRight, kRightToLeft };
// "top_to_bottom", "bottom_to_top", "left_to_right", "right_to_left"; false for anything else.
bool ParseReadoutOrder(const std::string& text, ReadoutOrder* order);
// The name ParseReadoutOrder reads ("top_to_bottom", ...).
const char* ReadoutOrderName(ReadoutOrder order);

// Everything camera.json holds.
struct CameraFile {
  Camera camera;
  double depth_scale = 5000.0;            // raw depth units per metre
  bool depth_registered_to_color = true;  // depth pixels already aligned with colour pixels
  // Only for unregistered depth: intrinsics of the depth camera (camera above is the colour one)
  // and the transform taking points from the depth camera's frame to the colour camera's.
  std::optional<Camera> depth_camera;
  SE3 color_from_depth;
  // Seconds from the exposure of the depth image's first row to its last (0: a global shutter).
  // Absent: the tracker's setting, which is the Kinect v1's (registration/rolling_shutter.h).
  std::optional<double> depth_readout_s;
  // The order the depth image's lines were exposed in: "top_to_bottom", "bottom_to_top",
  // "left_to_right" or "right_to_left" (images turned in software after capture). Absent: the
  // tracker's setting (top to bottom).
  std::optional<ReadoutOrder> depth_readout_order;
};

// Reads camera.json; throws InputError naming the file on a missing file, bad JSON, a missing or
// wrongly typed field, or invalid or implausible intrinsics (Camera::CheckPlausible).
CameraFile LoadCameraFile(const std::string& path);
// Writes camera.json atomically (temporary name, then rename).
void SaveCameraFile(const std::string& path, const CameraFile& file);

}  // namespace gf
