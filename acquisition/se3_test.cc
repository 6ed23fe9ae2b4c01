#include "acquisition/se3.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace gf {
namespace {

SE3::Tangent RandomTangent(std::mt19937& rng, double max_angle) {
  std::normal_distribution<double> n(0, 1);
  std::uniform_real_distribution<double> angle(0, max_angle);
  Eigen::Vector3d axis(n(rng), n(rng), n(rng));
  SE3::Tangent xi;
  xi << n(rng), n(rng), n(rng), axis.normalized() * angle(rng);
  return xi;
}

void ExpectNear(const SE3& a, const SE3& b, double tol) {
  EXPECT_LT((a.Matrix() - b.Matrix()).norm(), tol) << a.Matrix() << "\nvs\n" << b.Matrix();
}

TEST(SE3, LogInvertsExpForAnglesUpToPi) {
  std::mt19937 rng(1);
  for (int i = 0; i < 2000; ++i) {
    const SE3::Tangent xi = RandomTangent(rng, M_PI - 1e-6);
    EXPECT_LT((SE3::Exp(xi).Log() - xi).norm(), 1e-8) << xi.transpose();
  }
}

TEST(SE3, ExpInvertsLogIncludingTinyAndHalfTurnRotations) {
  std::mt19937 rng(2);
  for (double angle : {0.0, 1e-12, 1e-7, 1e-3, 1.0, M_PI - 1e-9, M_PI}) {
    SE3::Tangent xi;
    xi << 0.3, -1.2, 2.0, Eigen::Vector3d(1, 2, -0.5).normalized() * angle;
    const SE3 t = SE3::Exp(xi);
    ExpectNear(SE3::Exp(t.Log()), t, 1e-9);
    EXPECT_NEAR(t.RotationAngle(), angle, 1e-9);
  }
}

TEST(SE3, ExpMatchesTheMatrixExponential) {
  // exp of the 4x4 twist matrix by a long Taylor series, independent of the closed form.
  SE3::Tangent xi;
  xi << 0.4, -0.1, 0.7, 0.2, -0.9, 0.5;
  Eigen::Matrix4d twist = Eigen::Matrix4d::Zero();
  twist.topLeftCorner<3, 3>() = Hat(xi.tail<3>());
  twist.topRightCorner<3, 1>() = xi.head<3>();
  Eigen::Matrix4d sum = Eigen::Matrix4d::Identity(), term = Eigen::Matrix4d::Identity();
  for (int k = 1; k < 40; ++k) {
    term = term * twist / k;
    sum += term;
  }
  EXPECT_LT((SE3::Exp(xi).Matrix() - sum).norm(), 1e-12);
}

TEST(SE3, CompositionInverseAndActionAgreeWithMatrices) {
  std::mt19937 rng(3);
  for (int i = 0; i < 200; ++i) {
    const SE3 a = SE3::Exp(RandomTangent(rng, 3.0));
    const SE3 b = SE3::Exp(RandomTangent(rng, 3.0));
    EXPECT_LT(((a * b).Matrix() - a.Matrix() * b.Matrix()).norm(), 1e-12);
    EXPECT_LT((a.Inverse().Matrix() - a.Matrix().inverse()).norm(), 1e-12);
    ExpectNear(a * a.Inverse(), SE3(), 1e-12);
    const Eigen::Vector3d p(0.5, -2, 3);
    EXPECT_LT((a * p - (a.Matrix() * p.homogeneous()).head<3>()).norm(), 1e-12);
    ExpectNear(SE3(a.ToIsometry()), a, 1e-12);
  }
}

TEST(SE3, FromMatrixOrthonormalisesRoundedRotations) {
  const SE3 t = SE3::Exp((SE3::Tangent() << 1, 2, 3, 0.3, 0.2, 0.1).finished());
  Eigen::Matrix4d m = t.Matrix();
  m.topLeftCorner<3, 3>() += Eigen::Matrix3d::Constant(1e-7);  // as a text file rounds it
  const SE3 u = SE3::FromMatrix(m);
  EXPECT_NEAR(u.RotationMatrix().determinant(), 1.0, 1e-12);
  ExpectNear(u, t, 1e-6);
}

}  // namespace
}  // namespace gf
