#include "acquisition/trajectory_metrics.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/testing.h"

namespace gf {
namespace {

TEST(EvaluateTrajectory, RigidlyMovedCopyHasZeroErrorAndNoiseIsMeasured) {
  GF_REQUIRE_DATASET(tum, "tum_fr1_xyz_head");
  const Trajectory gt = ReadTumTrajectory(tum + "/groundtruth.txt");
  // The estimate lives in another world frame and is sampled at other times (within 5 ms).
  const SE3 other_from_world = SE3::Exp((SE3::Tangent() << 0.3, -1, 2, 0.4, 0.1, -0.7).finished());
  Trajectory est;
  for (size_t i = 0; i < gt.size(); i += 3) {
    StampedPose p = gt[i];
    p.timestamp += 0.004;
    p.timestamp_text.clear();
    p.world_from_camera = other_from_world * gt[i].world_from_camera;
    est.push_back(p);
  }
  TrajectoryErrorSummary s = EvaluateTrajectory(gt, est);
  ASSERT_TRUE(s.success) << s.message;
  EXPECT_EQ(s.pairs, static_cast<int>(est.size()));
  EXPECT_LT(s.ate_rmse_m, 1e-9);
  EXPECT_LT(s.rpe_trans_rmse_m, 1e-9);
  EXPECT_LT((s.gt_from_estimate.Matrix() - other_from_world.Inverse().Matrix()).norm(), 1e-6);

  // Isotropic noise of sigma per axis gives an ATE RMSE of about sigma * sqrt(3) (slightly less:
  // the alignment absorbs a little of it).
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0, 0.01);
  for (StampedPose& p : est)
    p.world_from_camera = SE3(
        p.world_from_camera.rotation(),
        p.world_from_camera.translation() + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  s = EvaluateTrajectory(gt, est);
  EXPECT_NEAR(s.ate_rmse_m, 0.01 * std::sqrt(3.0), 0.002);
}

TEST(EvaluateTrajectory, AssociationIsOneToOneWithinTheWindow) {
  Trajectory gt, est;
  for (int i = 0; i < 10; ++i) gt.push_back({i * 0.1, "", SE3()});
  for (double t : {0.005, 0.006, 0.31, 0.5}) est.push_back({t, "", SE3()});
  const auto pairs = AssociatePoses(gt, est, 0.02);
  // 0.005 takes gt 0.0; 0.006 finds it taken; 0.31 is 10 ms from 0.3; 0.5 matches exactly.
  ASSERT_EQ(pairs.size(), 3u);
  EXPECT_EQ(pairs[0], (std::pair<size_t, size_t>(0, 0)));
  EXPECT_EQ(pairs[1], (std::pair<size_t, size_t>(3, 2)));
  EXPECT_EQ(pairs[2], (std::pair<size_t, size_t>(5, 3)));
  EXPECT_FALSE(EvaluateTrajectory(gt, {est[0]}).success);
}

}  // namespace
}  // namespace gf
