// Planes through 3D points: the least-squares plane through a set, and the plane that most points
// lie near (RANSAC with a fixed seed, refined by least squares over its inliers). Used by the
// single-frame glass finder (the table under a glass, in the camera frame) and by the map's
// surfaces of revolution (the table a glass stands on, in the world frame).
//
// No threads, no I/O; the same points give the same plane on every run. Usage:
//   gf::FittedPlane p;
//   if (gf::RansacPlane(points, 0.01, 400, &p)) ...  // p.normal . x + p.offset = 0
#pragma once

#include <Eigen/Core>
#include <vector>

namespace gf {

struct FittedPlane {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // unit; its sign as RansacPlane says
  double offset = 0;                                 // normal . x + offset = 0 on the plane
  int inliers = 0;                                   // points within the inlier distance
};

// The unit normal of the least-squares plane through `points` about `mean` (their centroid): the
// smallest eigenvector of their scatter. Its sign is the solver's.
Eigen::Vector3d LeastSquaresNormal(const std::vector<Eigen::Vector3d>& points,
                                   const Eigen::Vector3d& mean);

// The plane with the most of `points` within inlier_m (metres) of it among `iterations` planes
// through three points drawn with a fixed seed, refined by least squares over those inliers; its
// normal points to the side of the origin (offset >= 0). False when no draw gives 3 inliers.
bool RansacPlane(const std::vector<Eigen::Vector3d>& points, double inlier_m, int iterations,
                 FittedPlane* plane);

// Up to `count` planes, largest first, each the RansacPlane of the points the ones before left
// (their inliers removed), while a plane holds at least min_inliers points.
std::vector<FittedPlane> RansacPlanes(std::vector<Eigen::Vector3d> points, double inlier_m,
                                      int iterations, int count, double min_inliers);

}  // namespace gf
