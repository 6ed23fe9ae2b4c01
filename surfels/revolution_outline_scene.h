// Tests only: a clear glass standing on a table in front of a textured wall, and grey views of
// it rendered by casting rays (surfels/revolution_outline_test.cc, surfels/revolution_test.cc).
// World frame: z up from the table (z = 0); the glass is an upright cylinder of kGlassRadius
// about the z axis, kGlassHeight tall; the wall is the plane y = kWallY behind it; the cameras
// look at it from negative y.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/se3.h"
#include "surfels/revolution_outline.h"

namespace gf::test_scene {

inline constexpr double kGlassRadius = 0.045, kGlassHeight = 0.2, kWallY = 0.15;

inline Camera SmallCamera() {
  Camera c;
  c.width = 320, c.height = 240, c.fx = c.fy = 300, c.cx = 159.5, c.cy = 119.5;
  return c;
}

// A value 64-191 per 2 cm square of the wall or the table: a texture of sharp edges.
inline double Texture(double a, double b) {
  uint32_t h = static_cast<uint32_t>(static_cast<int>(std::floor(a / 0.02)) + 1000) * 73856093u ^
               static_cast<uint32_t>(static_cast<int>(std::floor(b / 0.02)) + 1000) * 19349663u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  return 64 + h % 128;
}

// A camera at `eye` looking at `target`, x to the right, y down, the world's z up.
inline SE3 LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d y = -(up - up.dot(z) * z).normalized();
  Eigen::Matrix3d r;
  r << y.cross(z), y, z;
  return SE3(r, eye);
}

// Nine views 1 m from the glass's axis, 35 cm above the table, from 20 degrees to either side.
inline std::vector<SE3> Views() {
  std::vector<SE3> views;
  for (int k = -4; k <= 4; ++k) {
    const double a = k * 5.0 * M_PI / 180;
    views.push_back(LookAt({std::sin(a), -std::cos(a), 0.35}, {0, 0, 0.1}));
  }
  return views;
}

// What the camera sees: the wall (or the table) and, with `glass`, the glass showing it a little
// tinted and lit, and dark where the rays graze the glass (75 degrees or more from its normal:
// refraction there turns the light away, which gives a glass its dark rim).
inline cv::Mat Render(const Camera& camera, const SE3& world_from_camera, bool glass) {
  cv::Mat image(camera.height, camera.width, CV_8UC1);
  const Eigen::Vector3d e = world_from_camera.translation();
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const Eigen::Vector3d d =
          world_from_camera.rotation() * camera.BackProject(Eigen::Vector2d(x, y), 1.0);
      double value = 0;
      const double to_wall = d.y() > 0 ? (kWallY - e.y()) / d.y() : 1e30;
      const double to_table = d.z() < 0 ? -e.z() / d.z() : 1e30;
      if (to_wall < to_table) {
        const Eigen::Vector3d p = e + to_wall * d;
        value = Texture(p.x(), p.z());
      } else if (to_table < 1e30) {
        const Eigen::Vector3d p = e + to_table * d;
        value = Texture(p.x(), p.y());
      }
      const double a = d.x() * d.x() + d.y() * d.y(), b = 2 * (e.x() * d.x() + e.y() * d.y()),
                   c = e.x() * e.x() + e.y() * e.y() - kGlassRadius * kGlassRadius;
      const double disc = b * b - 4 * a * c;
      if (glass && disc > 0) {
        const double t = (-b - std::sqrt(disc)) / (2 * a), z = e.z() + t * d.z();
        const Eigen::Vector3d normal(e.x() + t * d.x(), e.y() + t * d.y(), 0);
        const double facing = -normal.normalized().dot(d.normalized());
        if (t > 0 && z >= 0 && z <= kGlassHeight)
          value = facing < std::cos(75 * M_PI / 180) ? 20 : 0.85 * value + 25;
      }
      image.at<uint8_t>(y, x) = static_cast<uint8_t>(std::min(255.0, value));
    }
  return image;
}

// The wall behind the glass as the map's opaque surfels would hold it, every centimetre.
inline std::vector<Eigen::Vector3d> WallPoints() {
  std::vector<Eigen::Vector3d> wall;
  for (double x = -0.3; x <= 0.3; x += 0.01)
    for (double z = 0.0; z <= kGlassHeight; z += 0.01) wall.emplace_back(x, kWallY, z);
  return wall;
}

// The glass as the outline search receives it: the read strip's middle at its front (the frame's
// origin on the table under it), facing the cameras, 2 cm to either side.
inline StandingObject FrontOfGlass(std::vector<Eigen::Vector3d> solid) {
  StandingObject s;
  s.origin = Eigen::Vector3d(0, -kGlassRadius, 0);
  s.height_m = kGlassHeight;
  s.outward = Eigen::Vector2d(0, -1);
  s.min_radius_m = 0.02;
  s.solid = std::move(solid);
  return s;
}

}  // namespace gf::test_scene
