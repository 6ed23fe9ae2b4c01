// The residual of a pose-graph edge (pose_graph.h), for Ceres' automatic differentiation; in its
// own header so that tests can check it with ceres::GradientChecker.
#pragma once

#include <ceres/autodiff_cost_function.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "acquisition/se3.h"

namespace gf {

// Parameters: quaternion (x, y, z, w) and translation of world_from_from, then of world_from_to.
// Residual: sqrt(information) [t_e; 2 vec(q_e)], where E = (world_from_from^-1 world_from_to)
// measured^-1 is the left error of the estimate (q_e taken with w >= 0).
class RelativePoseError {
 public:
  RelativePoseError(const SE3& from_from_to, const Eigen::Matrix<double, 6, 6>& information)
      : measured_q_(from_from_to.rotation()), measured_t_(from_from_to.translation()) {
    // information = L L^T: |L^T r|^2 = r^T information r.
    sqrt_information_ = information.llt().matrixL().transpose();
  }

  static ceres::CostFunction* Create(const SE3& from_from_to,
                                     const Eigen::Matrix<double, 6, 6>& information) {
    return new ceres::AutoDiffCostFunction<RelativePoseError, 6, 4, 3, 4, 3>(
        new RelativePoseError(from_from_to, information));
  }

  template <typename T>
  bool operator()(const T* q_from, const T* t_from, const T* q_to, const T* t_to,
                  T* residual) const {
    using Quaternion = Eigen::Quaternion<T>;
    using Vector3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Quaternion> qa(q_from), qb(q_to);
    const Eigen::Map<const Vector3> ta(t_from), tb(t_to);
    const Quaternion qa_inverse = qa.conjugate();
    const Quaternion q_estimate = qa_inverse * qb;
    const Vector3 t_estimate = qa_inverse * (tb - ta);
    Quaternion q_error = q_estimate * measured_q_.conjugate().template cast<T>();
    if (q_error.w() < T(0)) q_error.coeffs() *= T(-1);
    const Vector3 t_error = t_estimate - q_error * measured_t_.template cast<T>();
    Eigen::Matrix<T, 6, 1> r;
    r.template head<3>() = t_error;
    r.template tail<3>() = T(2) * q_error.vec();
    Eigen::Map<Eigen::Matrix<T, 6, 1>> out(residual);
    out = sqrt_information_.template cast<T>() * r;
    return true;
  }

 private:
  Eigen::Quaterniond measured_q_;
  Eigen::Vector3d measured_t_;
  Eigen::Matrix<double, 6, 6> sqrt_information_;
};

}  // namespace gf
