// Dense projective point-to-plane ICP with an optional feature term: the paper's joint cost
// (Henry et al., RGB-D Mapping; KinectFusion's projective association).
//
// Estimates reference_from_current, the pose of the current camera in the reference camera's frame,
// by Gauss-Newton over a coarse-to-fine depth pyramid. Each valid current pixel is moved into the
// reference camera, projected, and paired with the reference vertex there (projective data
// association); pairs farther apart than max_distance_m or with normals more than
// max_normal_angle_deg apart are rejected. Residuals:
//   point-to-plane   n_ref . (T p_cur - q_ref)                (metres, / plane_sigma_m)
//   feature          project(T p_cur) - u_ref                 (pixels, / feature_sigma_px)
// both with Huber weights. Increments are applied on the left: T <- exp(xi) T, xi = [rho; phi].
//
// No threads, no I/O. Usage:
//   gf::IcpSummary s = gf::AlignPointToPlane(ref_pyramid, cur_pyramid, guess, gf::IcpOptions{});
//   if (s.success) reference_from_current = s.reference_from_current;
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/se3.h"
#include "registration/depth_pyramid.h"

namespace gf {

struct IcpOptions {
  std::vector<int> iterations = {10, 6, 2};  // Gauss-Newton steps per level, coarsest first
  double max_distance_m = 0.08;              // reject pairs farther apart, metres
  double max_normal_angle_deg = 30.0;        // reject pairs whose normals differ more, degrees
  double plane_sigma_m = 0.01;               // point-to-plane residual scale at 1 m, metres
  // Depth-dependent scale (Kinect noise grows with depth squared): the residual of a pair at depth
  // z is divided by plane_sigma_m * sigma(z) / sigma(1 m), sigma(z) = a + b (z - 0.4)^2.
  bool depth_weighting = true;
  double noise_a_m = 0.0012;      // a, metres (Nguyen et al. 2012)
  double noise_b_per_m = 0.0019;  // b, 1/metres
  double plane_huber = 1.0;       // Huber threshold in units of plane_sigma_m
  double feature_sigma_px = 2.0;  // feature reprojection scale, pixels
  double feature_huber = 2.0;     // Huber threshold in units of feature_sigma_px
  double feature_weight = 1.0;    // multiplies every feature term (0 = dense only)
  // Features pull the coarse levels into the right basin; finer levels (index < this, 0 = full
  // resolution) are left to the dense term, which is more precise there.
  int feature_min_level = 1;
  int min_inliers = 1000;          // fewer pairs at the finest level: failure
  double max_rmse_m = 0.03;        // larger final point-to-plane RMSE: failure
  double convergence_step = 1e-6;  // stop a level when |xi| falls below, m / rad (at most 1)
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

// A sparse correspondence for the joint cost: a point seen in the current frame (3D, current
// camera, metres) and where the same feature lies in the reference image (pixels, level 0).
struct FeatureCorrespondence {
  Eigen::Vector3d point_in_current;
  Eigen::Vector2d pixel_in_reference;
};

struct IcpSummary {
  bool success = false;
  std::string termination;  // "converged", "max iterations", or why it failed
  SE3 reference_from_current;
  int iterations = 0;          // over all levels
  int inliers = 0;             // point pairs at the finest level
  int valid_points = 0;        // current pixels with a vertex and normal at the finest level
  int overlapping_points = 0;  // of those, landing on a reference pixel with a vertex and normal
  double rmse_m = 0;           // point-to-plane RMSE of the inliers at the finest level
  int feature_inliers = 0;     // features within the Huber threshold at the end
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();  // J^T W J
  std::string BriefReport() const;
};

IcpSummary AlignPointToPlane(const DepthPyramid& reference, const DepthPyramid& current,
                             const SE3& initial_reference_from_current, const IcpOptions& options,
                             const std::vector<FeatureCorrespondence>& features = {});

// The residuals of the joint cost with their Jacobians with respect to a left increment xi of
// T = reference_from_current (used by the solver, and checked by ceres::GradientChecker in tests).
double PointToPlaneResidual(const SE3& reference_from_current,
                            const Eigen::Vector3d& point_in_current,
                            const Eigen::Vector3d& point_in_reference,
                            const Eigen::Vector3d& normal_in_reference,
                            Eigen::Matrix<double, 1, 6>* jacobian);
Eigen::Vector2d ReprojectionResidual(const SE3& reference_from_current, const Camera& camera,
                                     const Eigen::Vector3d& point_in_current,
                                     const Eigen::Vector2d& pixel_in_reference,
                                     Eigen::Matrix<double, 2, 6>* jacobian);

}  // namespace gf
