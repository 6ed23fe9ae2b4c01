#include "registration/ransac.h"

#include <gtest/gtest.h>

#include <random>

namespace gf {
namespace {

TEST(EstimateRigidRansac, RecoversAPoseDespite60PercentOutliers) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> noise(0, 0.003);
  const SE3 truth = SE3::Exp((SE3::Tangent() << 0.2, -0.1, 0.05, 0.1, 0.3, -0.2).finished());
  std::vector<Eigen::Vector3d> source, target;
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d p(u(rng), u(rng), 2 + u(rng));
    source.push_back(p);
    if (i < 80) {
      target.push_back(truth * p + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
    } else {
      target.push_back(Eigen::Vector3d(u(rng), u(rng), 2 + u(rng)));  // wrong match
    }
  }
  const RansacReport r = EstimateRigidRansac(source, target, RansacOptions{});
  ASSERT_TRUE(r.success) << r.BriefReport();
  EXPECT_GE(r.inliers, 75);
  EXPECT_LE(r.inliers, 90);
  const SE3 error = truth.Inverse() * r.target_from_source;
  EXPECT_LT(error.TranslationNorm(), 0.005) << r.BriefReport();
  EXPECT_LT(error.RotationAngle() * 180 / M_PI, 0.3);
  EXPECT_LT(r.rmse_m, 0.01);
  // Adaptive: with 40% inliers, 0.995 confidence needs about 80 samples, far below the cap.
  EXPECT_LT(r.iterations, 300);
  // Same seed, same answer.
  const RansacReport again = EstimateRigidRansac(source, target, RansacOptions{});
  EXPECT_EQ(again.inlier_indices, r.inlier_indices);
}

TEST(EstimateRigidRansac, FailsCleanlyOnRandomCorrespondences) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::Vector3d> source, target;
  for (int i = 0; i < 50; ++i) {
    source.emplace_back(u(rng), u(rng), 2 + u(rng));
    target.emplace_back(u(rng), u(rng), 2 + u(rng));
  }
  const RansacReport r = EstimateRigidRansac(source, target, RansacOptions{});
  EXPECT_FALSE(r.success);
  EXPECT_EQ(r.termination, "too few inliers");
  EXPECT_FALSE(EstimateRigidRansac({source[0]}, {target[0]}, RansacOptions{}).success);
}

}  // namespace
}  // namespace gf
