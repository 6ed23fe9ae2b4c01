#include "acquisition/camera.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <sstream>
#include <tuple>
#include <utility>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/names.h"

namespace gf {

bool Camera::Check(std::string* message) const {
  auto fail = [&](const std::string& m) {
    if (message) *message = m;
    return false;
  };
  if (width <= 0 || height <= 0) return fail("image size must be positive");
  if (!(fx > 0) || !(fy > 0) || !std::isfinite(fx) || !std::isfinite(fy))
    return fail("focal lengths fx, fy must be positive and finite");
  if (!std::isfinite(cx) || !std::isfinite(cy)) return fail("principal point must be finite");
  for (double d : distortion)
    if (!std::isfinite(d)) return fail("distortion coefficients must be finite");
  return true;
}

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

// Degrees the image spans along one axis, from the outer edge of its first pixel to that of its
// last: the principal point splits it into two angles.
double FieldOfViewDeg(int size, double focal, double centre) {
  return (std::atan((centre + 0.5) / focal) + std::atan((size - 0.5 - centre) / focal)) * kRadToDeg;
}

std::string DistortionText(const std::vector<double>& d) {
  std::string text = "[";
  for (size_t i = 0; i < d.size(); ++i) text += (i ? ", " : "") + FormatNumber(d[i]);
  return text + "]";
}

// Empty when r_d(r) = r radial(r^2) (LensModel) grows from the axis until it reaches corner_radius
// (the corners' distorted normalised radius), else why not.
std::string RadialProblem(const std::array<double, 8>& d, double corner_radius) {
  const double k1 = d[0], k2 = d[1], k3 = d[4], k4 = d[5], k5 = d[6], k6 = d[7];
  // The farthest ray the model may need: kMaxFieldOfViewDeg / 2 off the axis.
  const double max_r = std::tan(kMaxFieldOfViewDeg / 2 / kRadToDeg);
  const double step = corner_radius / 1000;  // a thousandth of the way to the corners
  for (double r = 0; r <= max_r; r += step) {
    const double r2 = r * r;
    // r_d = r N / D; its slope is ((N + r N') D - N r D') / D^2, and D must stay positive.
    const double n = 1 + r2 * (k1 + r2 * (k2 + r2 * k3)), d = 1 + r2 * (k4 + r2 * (k5 + r2 * k6));
    const double n_slope = 1 + r2 * (3 * k1 + r2 * (5 * k2 + r2 * 7 * k3));  // N + r N'
    const double r_d_prime = r2 * (2 * k4 + r2 * (4 * k5 + r2 * 6 * k6));     // r D'
    if (d > 0 && r * n / d >= corner_radius) return "";
    const double slope = d > 0 ? n_slope * d - n * r_d_prime : 0;
    if (!(slope > 0)) {
      char text[160];
      std::snprintf(text, sizeof(text),
                    "stops growing at normalised radius %.3g, inside the image (its corners lie "
                    "at %.3g): pixels beyond have no ray",
                    r, corner_radius);
      return text;
    }
  }
  char text[160];
  std::snprintf(text, sizeof(text),
                "maps no ray within %.0f degrees of the axis to the image's corners (normalised "
                "radius %.3g)",
                kMaxFieldOfViewDeg / 2, corner_radius);
  return text;
}

}  // namespace

bool Camera::CheckPlausible(std::string* message) const {
  if (!Check(message)) return false;
  auto fov = [](const char* field, double focal, double degrees) {
    char text[160];
    std::snprintf(text, sizeof(text), "%s %s gives a %.1f degree field of view; expected %.0f-%.0f",
                  field, FormatNumber(focal).c_str(), degrees, kMinFieldOfViewDeg,
                  kMaxFieldOfViewDeg);
    return std::string(text);
  };
  auto outside = [](const char* field, double centre, int size) {
    return std::string(field) + " " + FormatNumber(centre) + " lies outside the image (-0.5 to " +
           FormatNumber(size - 0.5) + " pixels)";
  };
  const double fov_x = FieldOfViewDeg(width, fx, cx), fov_y = FieldOfViewDeg(height, fy, cy);
  double corner_radius = 0;
  for (double u : {-0.5, width - 0.5})
    for (double v : {-0.5, height - 0.5})
      corner_radius = std::max(corner_radius, std::hypot((u - cx) / fx, (v - cy) / fy));
  FieldCheck c(message);
  c.Require(width >= kMinImageWidthPx && height >= kMinImageHeightPx,
            "width " + std::to_string(width) + " and height " + std::to_string(height) +
                " make an image smaller than the least GlassFusion works on (" +
                std::to_string(kMinImageWidthPx) + "x" + std::to_string(kMinImageHeightPx) + ")")
      .In("width", width, kMinImageWidthPx, kMaxImageSidePx, kLargerThanAnyImage)
      .In("height", height, kMinImageHeightPx, kMaxImageSidePx, kLargerThanAnyImage)
      .Require(cx >= -0.5 && cx <= width - 0.5, outside("cx", cx, width))
      .Require(cy >= -0.5 && cy <= height - 0.5, outside("cy", cy, height))
      .Require(fov_x >= kMinFieldOfViewDeg && fov_x <= kMaxFieldOfViewDeg, fov("fx", fx, fov_x))
      .Require(fov_y >= kMinFieldOfViewDeg && fov_y <= kMaxFieldOfViewDeg, fov("fy", fy, fov_y));
  if (!c.ok()) return false;
  const std::string radial = RadialProblem(distortion, corner_radius);
  c.Require(radial.empty(),
            "distortion " + DistortionText(DistortionCoefficients()) + ": its radial part " +
                radial);
  return c.ok();
}

bool Camera::HasDistortion() const {
  for (double d : distortion)
    if (d != 0.0) return true;
  return false;
}

std::vector<double> Camera::DistortionCoefficients() const {
  const bool rational = distortion[5] != 0 || distortion[6] != 0 || distortion[7] != 0;
  return std::vector<double>(distortion.begin(), distortion.begin() + (rational ? 8 : 5));
}

bool Camera::operator==(const Camera& o) const {
  return width == o.width && height == o.height && fx == o.fx && fy == o.fy && cx == o.cx &&
         cy == o.cy && distortion == o.distortion;
}

namespace {

// Values computed from a camera alone, kept for the last few cameras a process met (a run meets
// one or two), so that per-pair code does not recompute them. Safe to call from any thread.
template <typename Value>
class PerCamera {
 public:
  template <typename Make>
  Value Get(const Camera& camera, Make make) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [c, v] : entries_)
      if (c == camera) return v;
    Value v = make();
    if (entries_.size() == kKept) entries_.erase(entries_.begin());
    entries_.emplace_back(camera, v);
    return v;
  }

 private:
  static constexpr size_t kKept = 4;
  std::mutex mutex_;
  std::vector<std::pair<Camera, Value>> entries_;
};

}  // namespace

void Camera::UndistortionMaps(cv::Mat* map1, cv::Mat* map2) const {
  static PerCamera<std::pair<cv::Mat, cv::Mat>> cache;
  std::tie(*map1, *map2) = cache.Get(*this, [&] {
    std::pair<cv::Mat, cv::Mat> maps;
    cv::initUndistortRectifyMap(CvK(), CvDistortion(), cv::Mat(), CvK(), cv::Size(width, height),
                                CV_16SC2, maps.first, maps.second);
    return maps;
  });
}

Eigen::Vector2d Camera::Project(const Eigen::Vector3d& p) const {
  return {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy};
}

Eigen::Vector3d Camera::BackProject(const Eigen::Vector2d& pixel, double depth) const {
  return {(pixel.x() - cx) / fx * depth, (pixel.y() - cy) / fy * depth, depth};
}

Eigen::Vector2d Camera::Distort(const Eigen::Vector2d& n) const {
  Eigen::Vector2d d;
  LensModel<double>(distortion).Distort(n.x(), n.y(), &d.x(), &d.y());
  return d;
}

Eigen::Vector2d Camera::Undistort(const Eigen::Vector2d& d) const {
  // Fixed-point iteration n <- (d - tangential(n)) / radial(n), as OpenCV does; converges quickly
  // for the mild distortion of depth cameras.
  const LensModel<double> lens(distortion);
  Eigen::Vector2d n = d;
  for (int i = 0; i < 50; ++i) {
    const double x = n.x(), y = n.y();
    const double r2 = x * x + y * y;
    const double radial = lens.Radial(r2);
    Eigen::Vector2d next((d.x() - lens.TangentialX(x, y, r2)) / radial,
                         (d.y() - lens.TangentialY(x, y, r2)) / radial);
    if ((next - n).squaredNorm() < 1e-24) return next;
    n = next;
  }
  return n;
}

Eigen::Vector2d Camera::ProjectDistorted(const Eigen::Vector3d& p) const {
  const Eigen::Vector2d d = Distort({p.x() / p.z(), p.y() / p.z()});
  return {fx * d.x() + cx, fy * d.y() + cy};
}

Eigen::Matrix3d Camera::K() const {
  Eigen::Matrix3d k;
  k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return k;
}

cv::Mat Camera::CvK() const { return (cv::Mat_<double>(3, 3) << fx, 0, cx, 0, fy, cy, 0, 0, 1); }

cv::Mat Camera::CvDistortion() const {
  return cv::Mat(1, 8, CV_64F, const_cast<double*>(distortion.data())).clone();
}

Camera Camera::Scaled(double factor) const {
  Camera c = *this;
  c.width = static_cast<int>(std::lround(width * factor));
  c.height = static_cast<int>(std::lround(height * factor));
  c.fx = fx * factor;
  c.fy = fy * factor;
  // Pixel centres: continuous coordinate u maps to (u + 0.5) * factor - 0.5.
  c.cx = (cx + 0.5) * factor - 0.5;
  c.cy = (cy + 0.5) * factor - 0.5;
  return c;
}

UndistortedPixels::UndistortedPixels(const Camera& camera)
    : camera_(camera), distorted_(camera.HasDistortion()) {
  if (!distorted_) return;
  nodes_x_ = (camera.width - 1 + kStep - 1) / kStep + 1;
  nodes_y_ = (camera.height - 1 + kStep - 1) / kStep + 1;
  using Nodes = std::vector<Eigen::Vector2d>;
  static PerCamera<std::shared_ptr<const Nodes>> cache;
  nodes_ = cache.Get(camera, [&] {
    auto nodes = std::make_shared<Nodes>(static_cast<size_t>(nodes_x_) * nodes_y_);
    for (int j = 0; j < nodes_y_; ++j)
      for (int i = 0; i < nodes_x_; ++i) {
        const Eigen::Vector2d n = camera.UndistortPixel({i * kStep, j * kStep});
        (*nodes)[j * nodes_x_ + i] = {camera.fx * n.x() + camera.cx, camera.fy * n.y() + camera.cy};
      }
    return std::shared_ptr<const Nodes>(std::move(nodes));
  });
}

namespace {

double Number(const nlohmann::json& j, const std::string& where, const char* key,
              const std::string& path) {
  if (!j.contains(key)) throw InputError(path, "missing field \"" + where + key + "\"");
  if (!j[key].is_number()) throw InputError(path, "field \"" + where + key + "\" must be a number");
  return j[key].get<double>();
}

std::vector<double> Numbers(const nlohmann::json& j, const std::string& name, size_t max_size,
                            const std::string& path) {
  if (!j.is_array() || j.size() > max_size)
    throw InputError(path, "\"" + name + "\" must be an array of at most " +
                               std::to_string(max_size) + " numbers");
  std::vector<double> values;
  for (const auto& v : j) {
    if (!v.is_number()) throw InputError(path, "\"" + name + "\" must hold numbers only");
    values.push_back(v.get<double>());
  }
  return values;
}

// The intrinsics part of camera.json (top level, or the "depth_camera" object).
Camera ParseIntrinsics(const nlohmann::json& j, const std::string& where, const std::string& path) {
  Camera c;
  const double width = Number(j, where, "width", path), height = Number(j, where, "height", path);
  if (width != std::floor(width) || height != std::floor(height))
    throw InputError(path, where + "width and height must be integers");
  // Before they are made ints (CheckPlausible checks the size again, with the least one).
  std::string problem;
  FieldCheck size(&problem);
  size.In("width", width, 1, kMaxImageSidePx, kLargerThanAnyImage)
      .In("height", height, 1, kMaxImageSidePx, kLargerThanAnyImage);
  if (!size.ok()) throw InputError(path, where + problem);
  c.width = static_cast<int>(width);
  c.height = static_cast<int>(height);
  c.fx = Number(j, where, "fx", path);
  c.fy = Number(j, where, "fy", path);
  c.cx = Number(j, where, "cx", path);
  c.cy = Number(j, where, "cy", path);
  if (j.contains("distortion")) {
    const std::vector<double> d = Numbers(j["distortion"], where + "distortion", 8, path);
    std::copy(d.begin(), d.end(), c.distortion.begin());
  }
  if (!c.CheckPlausible(&problem)) throw InputError(path, where + problem);
  return c;
}

nlohmann::ordered_json IntrinsicsJson(const Camera& c) {
  nlohmann::ordered_json j;
  j["width"] = c.width;
  j["height"] = c.height;
  j["fx"] = c.fx;
  j["fy"] = c.fy;
  j["cx"] = c.cx;
  j["cy"] = c.cy;
  j["distortion"] = c.DistortionCoefficients();
  return j;
}

}  // namespace

namespace {
constexpr std::pair<const char*, ReadoutOrder> kReadoutOrders[] = {
    {"top_to_bottom", ReadoutOrder::kTopToBottom},
    {"bottom_to_top", ReadoutOrder::kBottomToTop},
    {"left_to_right", ReadoutOrder::kLeftToRight},
    {"right_to_left", ReadoutOrder::kRightToLeft}};
}  // namespace

bool ParseReadoutOrder(const std::string& text, ReadoutOrder* order) {
  return ValueOfName(kReadoutOrders, text, order);
}

const char* ReadoutOrderName(ReadoutOrder order) { return NameOfValue(kReadoutOrders, order); }

CameraFile LoadCameraFile(const std::string& path) {
  const std::string text = ReadTextFile(path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, std::string("not valid JSON (") + e.what() + ")");
  }
  if (!j.is_object()) throw InputError(path, "expected a JSON object");
  CameraFile file;
  file.camera = ParseIntrinsics(j, "", path);
  if (j.contains("depth_scale")) {
    file.depth_scale = Number(j, "", "depth_scale", path);
    if (!(file.depth_scale > 0) || !std::isfinite(file.depth_scale))
      throw InputError(path, "\"depth_scale\" must be a positive number of depth units per metre");
  }
  if (j.contains("depth_registered_to_color")) {
    if (!j["depth_registered_to_color"].is_boolean())
      throw InputError(path, "\"depth_registered_to_color\" must be true or false");
    file.depth_registered_to_color = j["depth_registered_to_color"].get<bool>();
  }
  if (j.contains("depth_camera")) {
    if (!j["depth_camera"].is_object())
      throw InputError(path, "\"depth_camera\" must be an object of intrinsics");
    file.depth_camera = ParseIntrinsics(j["depth_camera"], "depth_camera.", path);
  }
  if (j.contains("color_from_depth")) {
    const auto& t = j["color_from_depth"];
    if (!t.is_object() || !t.contains("rotation") || !t.contains("translation"))
      throw InputError(path, "\"color_from_depth\" needs \"rotation\" (9) and \"translation\" (3)");
    const std::vector<double> r = Numbers(t["rotation"], "color_from_depth.rotation", 9, path);
    const std::vector<double> x =
        Numbers(t["translation"], "color_from_depth.translation", 3, path);
    if (r.size() != 9 || x.size() != 3)
      throw InputError(path, "\"color_from_depth\" needs 9 rotation and 3 translation numbers");
    Eigen::Matrix3d rotation;
    for (int i = 0; i < 9; ++i) rotation(i / 3, i % 3) = r[i];
    if ((rotation * rotation.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-3 ||
        rotation.determinant() < 0)
      throw InputError(path, "\"color_from_depth.rotation\" is not a rotation matrix");
    file.color_from_depth = SE3(rotation, Eigen::Vector3d(x[0], x[1], x[2]));
  }
  if (j.contains("depth_readout_s")) {
    const double readout = Number(j, "", "depth_readout_s", path);
    if (!(readout >= 0 && readout < 1))
      throw InputError(path, "\"depth_readout_s\" must be a number of seconds in [0, 1)");
    file.depth_readout_s = readout;
  }
  if (j.contains("depth_readout_order")) {
    if (!j["depth_readout_order"].is_string())
      throw InputError(path, "\"depth_readout_order\" must be a string");
    ReadoutOrder order;
    if (!ParseReadoutOrder(j["depth_readout_order"].get<std::string>(), &order))
      throw InputError(path,
                       "\"depth_readout_order\" must be top_to_bottom, bottom_to_top, "
                       "left_to_right or right_to_left");
    file.depth_readout_order = order;
  }
  if (!file.depth_registered_to_color && !file.depth_camera)
    throw InputError(
        path, "depth is not registered to colour but \"depth_camera\" intrinsics are missing");
  return file;
}

void SaveCameraFile(const std::string& path, const CameraFile& file) {
  nlohmann::ordered_json j = IntrinsicsJson(file.camera);
  j["depth_scale"] = file.depth_scale;
  j["depth_registered_to_color"] = file.depth_registered_to_color;
  if (file.depth_readout_s) j["depth_readout_s"] = *file.depth_readout_s;
  if (file.depth_readout_order) j["depth_readout_order"] = ReadoutOrderName(*file.depth_readout_order);
  if (file.depth_camera) {
    j["depth_camera"] = IntrinsicsJson(*file.depth_camera);
    const Eigen::Matrix3d r = file.color_from_depth.RotationMatrix();
    std::vector<double> rotation;
    for (int i = 0; i < 9; ++i) rotation.push_back(r(i / 3, i % 3));
    const Eigen::Vector3d& t = file.color_from_depth.translation();
    j["color_from_depth"] = {{"rotation", rotation}, {"translation", {t.x(), t.y(), t.z()}}};
  }
  WriteTextFileAtomically(path, j.dump(2) + "\n");
}

}  // namespace gf
