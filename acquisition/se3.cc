#include "acquisition/se3.h"

#include <cmath>

namespace gf {
namespace {
constexpr double kSmallAngle = 1e-8;

Eigen::Quaterniond Normalized(Eigen::Quaterniond q) {
  q.normalize();
  // One representative of q and -q keeps comparisons and printing stable.
  if (q.w() < 0) q.coeffs() *= -1.0;
  return q;
}

// V(phi) of the SE(3) exponential and its inverse.
Eigen::Matrix3d LeftJacobian(const Eigen::Vector3d& phi) {
  const double theta = phi.norm();
  const Eigen::Matrix3d W = Hat(phi);
  if (theta < 1e-5) return Eigen::Matrix3d::Identity() + 0.5 * W + W * W / 6.0;
  const double t2 = theta * theta;
  return Eigen::Matrix3d::Identity() + (1.0 - std::cos(theta)) / t2 * W +
         (theta - std::sin(theta)) / (t2 * theta) * W * W;
}

Eigen::Matrix3d InverseLeftJacobian(const Eigen::Vector3d& phi) {
  const double theta = phi.norm();
  const Eigen::Matrix3d W = Hat(phi);
  if (theta < 1e-5) return Eigen::Matrix3d::Identity() - 0.5 * W + W * W / 12.0;
  const double c =
      (1.0 - theta * std::sin(theta) / (2.0 * (1.0 - std::cos(theta)))) / (theta * theta);
  return Eigen::Matrix3d::Identity() - 0.5 * W + c * W * W;
}
}  // namespace

Eigen::Matrix3d Hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Eigen::Matrix3d SO3Exp(const Eigen::Vector3d& phi) {
  const double theta = phi.norm();
  if (theta < kSmallAngle) return Eigen::Matrix3d::Identity() + Hat(phi);
  return Eigen::AngleAxisd(theta, phi / theta).toRotationMatrix();
}

Eigen::Vector3d SO3Log(const Eigen::Quaterniond& q_in) {
  const Eigen::Quaterniond q = Normalized(q_in);
  const double n = q.vec().norm();
  if (n < kSmallAngle) return 2.0 * q.vec();        // first order: q ~ (1, phi/2)
  const double theta = 2.0 * std::atan2(n, q.w());  // in [0, pi] since w >= 0
  return theta / n * q.vec();
}

SE3::SE3(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translation)
    : rotation_(Normalized(rotation)), translation_(translation) {}

SE3::SE3(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation)
    : rotation_(Normalized(Eigen::Quaterniond(rotation))), translation_(translation) {}

SE3::SE3(const Eigen::Isometry3d& isometry)
    : SE3(Eigen::Matrix3d(isometry.rotation()), isometry.translation()) {}

SE3 SE3::FromMatrix(const Eigen::Matrix4d& m) {
  // Nearest rotation in the Frobenius norm: U V^T of the SVD.
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(m.topLeftCorner<3, 3>(),
                                        Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d r = svd.matrixU() * svd.matrixV().transpose();
  if (r.determinant() < 0) {
    Eigen::Matrix3d u = svd.matrixU();
    u.col(2) *= -1.0;
    r = u * svd.matrixV().transpose();
  }
  return SE3(r, m.topRightCorner<3, 1>());
}

SE3 SE3::Exp(const Tangent& xi) {
  const Eigen::Vector3d rho = xi.head<3>();
  const Eigen::Vector3d phi = xi.tail<3>();
  const double theta = phi.norm();
  Eigen::Quaterniond q;
  if (theta < kSmallAngle) {
    q = Eigen::Quaterniond(1.0, 0.5 * phi.x(), 0.5 * phi.y(), 0.5 * phi.z());
  } else {
    q = Eigen::Quaterniond(Eigen::AngleAxisd(theta, phi / theta));
  }
  return SE3(q, LeftJacobian(phi) * rho);
}

SE3::Tangent SE3::Log() const {
  Tangent xi;
  const Eigen::Vector3d phi = SO3Log(rotation_);
  xi.head<3>() = InverseLeftJacobian(phi) * translation_;
  xi.tail<3>() = phi;
  return xi;
}

SE3 SE3::Inverse() const {
  const Eigen::Quaterniond r = rotation_.conjugate();
  return SE3(r, -(r * translation_));
}

SE3 SE3::operator*(const SE3& other) const {
  return SE3(rotation_ * other.rotation_, rotation_ * other.translation_ + translation_);
}

Eigen::Matrix4d SE3::Matrix() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = RotationMatrix();
  m.topRightCorner<3, 1>() = translation_;
  return m;
}

Eigen::Isometry3d SE3::ToIsometry() const {
  Eigen::Isometry3d iso = Eigen::Isometry3d::Identity();
  iso.linear() = RotationMatrix();
  iso.translation() = translation_;
  return iso;
}

double SE3::RotationAngle() const { return SO3Log(rotation_).norm(); }

}  // namespace gf
