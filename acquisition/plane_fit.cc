#include "acquisition/plane_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>

namespace gf {

Eigen::Vector3d LeastSquaresNormal(const std::vector<Eigen::Vector3d>& points,
                                   const Eigen::Vector3d& mean) {
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : points) scatter += (p - mean) * (p - mean).transpose();
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvectors().col(0);
}

bool RansacPlane(const std::vector<Eigen::Vector3d>& points, double inlier_m, int iterations,
                 FittedPlane* plane) {
  if (points.size() < 3) return false;
  std::mt19937 random(12345);
  std::uniform_int_distribution<size_t> pick(0, points.size() - 1);
  int best = 0;
  Eigen::Vector3d best_n = Eigen::Vector3d::Zero();
  double best_d = 0;
  for (int it = 0; it < iterations; ++it) {
    const Eigen::Vector3d a = points[pick(random)], b = points[pick(random)],
                          c = points[pick(random)];
    Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() < 1e-9) continue;
    n.normalize();
    const double d = -n.dot(a);
    int inliers = 0;
    for (const Eigen::Vector3d& p : points) inliers += std::abs(n.dot(p) + d) < inlier_m;
    if (inliers > best) best = inliers, best_n = n, best_d = d;
  }
  if (best < 3) return false;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> inliers;
  for (const Eigen::Vector3d& p : points)
    if (std::abs(best_n.dot(p) + best_d) < inlier_m) inliers.push_back(p), mean += p;
  mean /= static_cast<double>(inliers.size());
  Eigen::Vector3d n = LeastSquaresNormal(inliers, mean);
  if (n.dot(best_n) < 0) n = -n;
  double d = -n.dot(mean);
  if (d < 0) n = -n, d = -d;
  *plane = {n, d, best};
  return true;
}

std::vector<FittedPlane> RansacPlanes(std::vector<Eigen::Vector3d> points, double inlier_m,
                                      int iterations, int count, double min_inliers) {
  std::vector<FittedPlane> planes;
  FittedPlane plane;
  while (static_cast<int>(planes.size()) < count &&
         RansacPlane(points, inlier_m, iterations, &plane) && plane.inliers >= min_inliers) {
    planes.push_back(plane);
    points.erase(std::remove_if(points.begin(), points.end(),
                                [&plane, inlier_m](const Eigen::Vector3d& p) {
                                  return std::abs(plane.normal.dot(p) + plane.offset) < inlier_m;
                                }),
                 points.end());
  }
  return planes;
}

}  // namespace gf
