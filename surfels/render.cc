#include "surfels/render.h"

#include <algorithm>
#include <cmath>

#include "acquisition/errors.h"
#include "acquisition/bounds.h"

namespace gf {

bool RenderOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.In("max_splat_px", max_splat_px, 0, kMaxImageSidePx, kLargerThanAnyImage)
      .Above("min_depth_m", min_depth_m, 0, kMaxDepthM, kFartherThanAnySensor);
  return c.ok();
}

SurfelImage RenderSurfels(const std::vector<Surfel>& surfels, const Camera& camera,
                          const SE3& world_from_camera, const RenderOptions& options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  SurfelImage out;
  out.color = cv::Mat(camera.height, camera.width, CV_8UC3, options.background);
  out.depth = cv::Mat::zeros(camera.height, camera.width, CV_32FC1);
  const SE3 camera_from_world = world_from_camera.Inverse();
  const Eigen::Matrix3d r = camera_from_world.RotationMatrix();
  const double focal = 0.5 * (camera.fx + camera.fy);
  for (const Surfel& s : surfels) {
    if (s.removed()) continue;
    const Eigen::Vector3d q = camera_from_world * s.position.cast<double>();
    if (q.z() < options.min_depth_m) continue;
    const Eigen::Vector2d uv = camera.ProjectDistorted(q);
    const int radius =
        std::min(options.max_splat_px, static_cast<int>(std::ceil(s.radius * focal / q.z() - 0.5)));
    const int cx = static_cast<int>(std::lround(uv.x())),
              cy = static_cast<int>(std::lround(uv.y()));
    if (cx + radius < 0 || cy + radius < 0 || cx - radius >= camera.width ||
        cy - radius >= camera.height)
      continue;
    double shade = 1.0;
    if (options.shade) {
      const Eigen::Vector3d n = r * s.normal.cast<double>();
      shade = 0.35 + 0.65 * std::abs(n.dot(q.normalized()));
    }
    const bool glass = s.source == static_cast<uint8_t>(DepthSource::kTransparent);
    // (glass: half the surfel's colour, half the tint's channel t)
    auto channel = [&](uint8_t c, uint8_t t) {
      return static_cast<uint8_t>((glass ? 0.5 * (c + t) : c) * shade + 0.5);
    };
    const cv::Vec3b& tint = options.glass_tint;
    const cv::Vec3b color(channel(s.blue, tint[0]), channel(s.green, tint[1]),
                          channel(s.red, tint[2]));
    const float z = static_cast<float>(q.z());
    for (int dy = -radius; dy <= radius; ++dy)
      for (int dx = -radius; dx <= radius; ++dx) {
        if (dx * dx + dy * dy > radius * radius + radius) continue;
        const int x = cx + dx, y = cy + dy;
        if (x < 0 || y < 0 || x >= camera.width || y >= camera.height) continue;
        float& d = out.depth.at<float>(y, x);
        if (d > 0 && d <= z) continue;
        d = z;
        out.color.at<cv::Vec3b>(y, x) = color;
      }
  }
  return out;
}

int CloseSplatGaps(cv::Mat* depth, const cv::Mat& fillable, int max_gap_px,
                   double max_relative_step) {
  GF_CHECK(depth && depth->type() == CV_32FC1, "CloseSplatGaps: a CV_32F depth image");
  GF_CHECK(fillable.empty() || (fillable.type() == CV_8UC1 && fillable.size() == depth->size()),
           "CloseSplatGaps: fillable is CV_8U of the depth's size");
  GF_CHECK(max_gap_px >= 0 && max_relative_step >= 0, "CloseSplatGaps: non-negative limits");
  const cv::Mat drawn = depth->clone();
  const int rows = drawn.rows, cols = drawn.cols;
  // The first drawn pixel from (x, y) in steps of (dx, dy), at most max_gap_px + 1 steps away:
  // its distance in steps (0: none) and depth.
  auto first_drawn = [&](int x, int y, int dx, int dy, float* z) {
    for (int step = 1; step <= max_gap_px + 1; ++step) {
      const int u = x + step * dx, v = y + step * dy;
      if (u < 0 || v < 0 || u >= cols || v >= rows) return 0;
      if ((*z = drawn.at<float>(v, u)) > 0) return step;
    }
    return 0;
  };
  constexpr int kDirections[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
  int filled = 0;
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x) {
      if (drawn.at<float>(y, x) > 0 || (!fillable.empty() && !fillable.at<uint8_t>(y, x)))
        continue;
      int best_span = max_gap_px + 2;
      float best = 0;
      for (const auto& d : kDirections) {
        float za = 0, zb = 0;
        const int a = first_drawn(x, y, d[0], d[1], &za);
        const int b = a ? first_drawn(x, y, -d[0], -d[1], &zb) : 0;
        if (!b || a + b >= best_span) continue;
        if (std::abs(za - zb) > max_relative_step * std::min(za, zb)) continue;
        best_span = a + b;
        best = (za * b + zb * a) / (a + b);  // linear along the span
      }
      if (best > 0) {
        depth->at<float>(y, x) = best;
        ++filled;
      }
    }
  return filled;
}

SE3 ViewOfMap(const std::vector<Surfel>& surfels, const Camera& camera,
              const Eigen::Vector3d& direction, const Eigen::Vector3d& up) {
  GF_CHECK(direction.norm() > 0 && up.cross(direction).norm() > 0,
           "a view needs a direction and an up that is not along it");
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  long n = 0;
  for (const Surfel& s : surfels)
    if (!s.removed()) centre += s.position.cast<double>(), ++n;
  if (n > 0) centre /= n;
  // The 90th percentile of distances from the centre: stray surfels do not set the framing.
  std::vector<double> distances;
  for (const Surfel& s : surfels)
    if (!s.removed()) distances.push_back((s.position.cast<double>() - centre).norm());
  double extent = 1.0;
  if (!distances.empty()) {
    std::nth_element(distances.begin(), distances.begin() + distances.size() * 9 / 10,
                     distances.end());
    extent = std::max(0.05, distances[distances.size() * 9 / 10]);
  }
  const double half_fov =
      std::atan(0.5 * std::min(camera.width / camera.fx, camera.height / camera.fy));
  const double distance = extent / std::tan(0.8 * half_fov);
  const Eigen::Vector3d z = direction.normalized();              // the camera's optical axis
  const Eigen::Vector3d y = (-up + up.dot(z) * z).normalized();  // image down: against `up`
  const Eigen::Vector3d x = y.cross(z);                          // image right (x cross y = z)
  Eigen::Matrix3d world_from_camera_rotation;
  world_from_camera_rotation << x, y, z;
  return SE3(world_from_camera_rotation, centre - distance * z);
}

}  // namespace gf
