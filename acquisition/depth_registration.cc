#include "acquisition/depth_registration.h"

#include <algorithm>
#include <cmath>

#include "acquisition/depth.h"
#include "acquisition/errors.h"

namespace gf {

void RegisterDepthToColor(const cv::Mat& depth_m, const cv::Mat& hole_mask,
                          const Camera& depth_camera, const Camera& color_camera,
                          const SE3& color_from_depth, cv::Mat* registered_depth,
                          cv::Mat* registered_holes) {
  GF_CHECK(depth_m.type() == CV_32FC1 && hole_mask.type() == CV_8UC1 &&
               depth_m.size() == hole_mask.size(),
           "need CV_32F depth and CV_8U hole mask of the same size");
  GF_CHECK(depth_m.cols == depth_camera.width && depth_m.rows == depth_camera.height,
           "depth image size differs from the depth camera");
  GF_CHECK(registered_depth && registered_holes, "outputs must not be null");
  const int w = color_camera.width, h = color_camera.height;
  cv::Mat zbuffer(h, w, CV_32FC1, cv::Scalar(std::numeric_limits<float>::infinity()));
  cv::Mat code(h, w, CV_8UC1, cv::Scalar(static_cast<uint8_t>(HoleCode::kOutOfRange)));
  cv::Mat valid_depth(h, w, CV_32FC1, cv::Scalar(0));
  const Eigen::Matrix3d R = color_from_depth.RotationMatrix();
  const Eigen::Vector3d t = color_from_depth.translation();
  // Footprint of one depth pixel in colour pixels, at equal depth.
  const double scale_x = color_camera.fx / depth_camera.fx,
               scale_y = color_camera.fy / depth_camera.fy;
  // With lens distortion: each pixel's ray, and a pixel's size where it lies (a wide lens's
  // pixels cover more of the scene towards the edges).
  const bool distorted = depth_camera.HasDistortion() || color_camera.HasDistortion();
  const UndistortedPixels rays(depth_camera);
  auto footprint = [&](int u, int v, const Eigen::Vector2d& ray) -> Eigen::Vector2d {
    if (!distorted) return {scale_x, scale_y};
    const int du = u + 1 < depth_camera.width ? 1 : -1, dv = v + 1 < depth_camera.height ? 1 : -1;
    return {color_camera.fx * std::abs(rays.Ray(u + du, v).x() - ray.x()),
            color_camera.fy * std::abs(rays.Ray(u, v + dv).y() - ray.y())};
  };

  auto splat = [&](int u, int v, double z, uint8_t hole_code, bool is_depth) {
    Eigen::Vector3d p;
    if (distorted) {
      const Eigen::Vector2d ray = rays.Ray(u, v);
      p = R * Eigen::Vector3d(ray.x() * z, ray.y() * z, z) + t;
    } else {
      p = R * depth_camera.BackProject({u, v}, z) + t;
    }
    if (p.z() <= 0) return;
    const Eigen::Vector2d c = distorted ? color_camera.ProjectDistorted(p) : color_camera.Project(p);
    const Eigen::Vector2d size = footprint(u, v, distorted ? rays.Ray(u, v) : Eigen::Vector2d());
    const double half_x = 0.5 * size.x() * z / p.z(), half_y = 0.5 * size.y() * z / p.z();
    const int x0 = std::max(0, static_cast<int>(std::ceil(c.x() - half_x - 0.5)));
    const int x1 = std::min(w - 1, static_cast<int>(std::floor(c.x() + half_x + 0.5)));
    const int y0 = std::max(0, static_cast<int>(std::ceil(c.y() - half_y - 0.5)));
    const int y1 = std::min(h - 1, static_cast<int>(std::floor(c.y() + half_y + 0.5)));
    for (int y = y0; y <= y1; ++y) {
      float* zb = zbuffer.ptr<float>(y);
      for (int x = x0; x <= x1; ++x) {
        if (p.z() >= zb[x]) continue;
        zb[x] = static_cast<float>(p.z());
        code.at<uint8_t>(y, x) = hole_code;
        valid_depth.at<float>(y, x) = is_depth ? static_cast<float>(p.z()) : 0.f;
      }
    }
  };

  for (int v = 0; v < depth_m.rows; ++v) {
    const float* d = depth_m.ptr<float>(v);
    const uint8_t* m = hole_mask.ptr<uint8_t>(v);
    int u = 0;
    while (u < depth_m.cols) {
      if (d[u] > 0) {
        splat(u, v, d[u], static_cast<uint8_t>(HoleCode::kValid), true);
        ++u;
        continue;
      }
      // A run of holes: place it at the far side's depth so it never hides a measured surface.
      const int start = u;
      while (u < depth_m.cols && !(d[u] > 0)) ++u;
      const float left = start > 0 ? d[start - 1] : 0.f;
      const float right = u < depth_m.cols ? d[u] : 0.f;
      const float z = std::max(left, right);
      if (!(z > 0)) continue;  // a row without any depth: nothing to place it by
      for (int i = start; i < u; ++i) splat(i, v, z, m[i], false);
    }
  }
  *registered_depth = valid_depth;
  *registered_holes = code;
}

}  // namespace gf
