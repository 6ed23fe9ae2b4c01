// Rigid-body transform (SE(3)) on Eigen, with exp/log maps and composition.
//
// Naming: a pose is named by the frames it maps between, target_from_source, so that
//   point_in_world = world_from_camera * point_in_camera
//   world_from_b   = world_from_a * a_from_b.
// Tangent vectors are ordered [rho; phi]: rho (metres) is the translational part of the twist,
// phi (radians) the rotation vector, as in Sophus and Ceres' conventions:
//   SE3::Exp([rho; phi]) = [ exp(phi^)  V(phi) rho ; 0 1 ].
//
// Thread-safety: a value type; const methods are safe to call concurrently.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace gf {

class SE3 {
 public:
  using Tangent = Eigen::Matrix<double, 6, 1>;

  SE3() : rotation_(Eigen::Quaterniond::Identity()), translation_(Eigen::Vector3d::Zero()) {}
  SE3(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translation);
  SE3(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation);
  explicit SE3(const Eigen::Isometry3d& isometry);
  // From a 4x4 rigid matrix; the rotation block is re-orthonormalised (file formats round it).
  static SE3 FromMatrix(const Eigen::Matrix4d& matrix);

  static SE3 Exp(const Tangent& xi);
  Tangent Log() const;

  SE3 Inverse() const;
  SE3 operator*(const SE3& other) const;
  Eigen::Vector3d operator*(const Eigen::Vector3d& point) const {
    return rotation_ * point + translation_;
  }

  const Eigen::Quaterniond& rotation() const { return rotation_; }
  const Eigen::Vector3d& translation() const { return translation_; }
  Eigen::Matrix3d RotationMatrix() const { return rotation_.toRotationMatrix(); }
  Eigen::Matrix4d Matrix() const;
  Eigen::Isometry3d ToIsometry() const;

  // Rotation angle in radians (0..pi) and translation length in metres.
  double RotationAngle() const;
  double TranslationNorm() const { return translation_.norm(); }

 private:
  Eigen::Quaterniond rotation_;  // unit quaternion, w >= 0
  Eigen::Vector3d translation_;
};

// Rotation-vector maps on SO(3), used by SE3 and by optimisers.
Eigen::Matrix3d SO3Exp(const Eigen::Vector3d& phi);
Eigen::Vector3d SO3Log(const Eigen::Quaterniond& q);
Eigen::Matrix3d Hat(const Eigen::Vector3d& v);

}  // namespace gf
