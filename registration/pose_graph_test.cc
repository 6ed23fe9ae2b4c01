#include "registration/pose_graph.h"

#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <set>

#include "registration/pose_graph_cost.h"

namespace gf {
namespace {

SE3 RandomPose(std::mt19937* rng, double translation_m, double rotation_rad) {
  std::normal_distribution<double> g(0, 1);
  SE3::Tangent xi;
  xi << translation_m * g(*rng), translation_m * g(*rng), translation_m * g(*rng),
      rotation_rad * g(*rng), rotation_rad * g(*rng), rotation_rad * g(*rng);
  return SE3::Exp(xi);
}

Matrix6d RandomInformation(std::mt19937* rng) {
  std::normal_distribution<double> g(0, 1);
  Matrix6d a;
  for (int i = 0; i < 36; ++i) a(i) = g(*rng);
  return a * a.transpose() + 0.5 * Matrix6d::Identity();
}

TEST(RelativePoseError, JacobiansPassCeresGradientChecker) {
  std::mt19937 rng(3);
  const ceres::EigenQuaternionManifold quaternion;
  const std::vector<const ceres::Manifold*> manifolds = {&quaternion, nullptr, &quaternion,
                                                         nullptr};
  ceres::NumericDiffOptions numeric;
  for (int trial = 0; trial < 20; ++trial) {
    const SE3 a = RandomPose(&rng, 1.0, 1.0), b = RandomPose(&rng, 1.0, 1.0);
    // A measurement near the truth, and one far from it (the error is then not small).
    const SE3 measured = (a.Inverse() * b) * RandomPose(&rng, trial % 2 ? 0.01 : 0.3, 0.2);
    std::unique_ptr<ceres::CostFunction> cost(
        RelativePoseError::Create(measured, RandomInformation(&rng)));
    Eigen::Vector4d qa = a.rotation().coeffs(), qb = b.rotation().coeffs();
    Eigen::Vector3d ta = a.translation(), tb = b.translation();
    std::vector<double*> parameters = {qa.data(), ta.data(), qb.data(), tb.data()};
    ceres::GradientChecker checker(cost.get(), &manifolds, numeric);
    ceres::GradientChecker::ProbeResults results;
    EXPECT_TRUE(checker.Probe(parameters.data(), 1e-7, &results)) << results.error_log;
  }
}

TEST(RelativePoseError, IsZeroAtTheMeasurementAndGrowsWithTheInformation) {
  std::mt19937 rng(5);
  const SE3 a = RandomPose(&rng, 1, 1), b = RandomPose(&rng, 1, 1);
  PoseGraph graph;
  graph.AddNode(0, a);
  graph.AddNode(1, b);
  PoseGraphEdge e{0, 1, a.Inverse() * b, Matrix6d::Identity() * 1e4,
                  PoseGraphEdge::Kind::kOdometry};
  EXPECT_NEAR(graph.Chi2(e), 0.0, 1e-12);
  // 1 cm off along x with sigma 1 cm: chi2 1.
  e.from_from_to =
      SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.01, 0, 0)) * e.from_from_to;
  EXPECT_NEAR(graph.Chi2(e), 1.0, 1e-6);
}

TEST(InformationWithFloor, AddsTheFloorAndKeepsUnconstrainedDirectionsFree) {
  // A plane seen head on: ICP constrains z translation and the two tilts, nothing else.
  Matrix6d icp = Matrix6d::Zero();
  icp(2, 2) = 1e8;
  icp(3, 3) = icp(4, 4) = 1e7;
  const Matrix6d info = InformationWithFloor(icp, 0.003, 0.004);
  const Matrix6d covariance = info.inverse();
  EXPECT_NEAR(std::sqrt(covariance(2, 2)), 0.003, 1e-4);  // the floor dominates
  EXPECT_GT(covariance(0, 0), 1e3);                       // x is free
  EXPECT_GT(covariance(5, 5), 1e3);                       // so is the roll about the axis
}

// The information of an alignment known to sigma_m and sigma_rad per axis.
Matrix6d Isotropic(double sigma_m, double sigma_rad) {
  return InformationWithFloor(Matrix6d::Identity() * 1e14, sigma_m, sigma_rad);
}

TEST(AlignmentInformation, GrowsWithTheChangeOfViewpoint) {
  AlignmentNoise noise;
  noise.floor_m = 0.003;
  noise.floor_deg = 0.2;
  noise.bias = 0.1;
  const Matrix6d icp = Matrix6d::Identity() * 1e14;  // an alignment sure of itself
  // 10 cm sideways and 3 degrees, over a scene 2 m away: a change of 0.1 + 2 * 0.052 m.
  const SE3 relative = SE3::Exp((SE3::Tangent() << 0.1, 0, 0, 0, 3 * M_PI / 180, 0).finished());
  const double change = relative.TranslationNorm() + 2.0 * relative.RotationAngle();
  const Matrix6d covariance = AlignmentInformation(icp, relative, 2.0, noise).inverse();
  EXPECT_NEAR(std::sqrt(covariance(0, 0)), 0.003 + 0.1 * change, 1e-6);
  EXPECT_NEAR(std::sqrt(covariance(3, 3)), 0.2 * M_PI / 180 + 0.1 * change / 2.0, 1e-6);
  // Without bias, the floor alone.
  noise.bias = 0;
  EXPECT_NEAR(std::sqrt(AlignmentInformation(icp, relative, 2.0, noise).inverse()(1, 1)), 0.003,
              1e-6);
}

// A camera going round a 2 m circle in `n` keyframes, odometry drifting (a bias in yaw and
// forward scale plus noise), the last keyframes closing the loop on the first.
struct LoopScenario {
  std::vector<SE3> truth, odometry;
  PoseGraph graph;
};

LoopScenario MakeLoop(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  LoopScenario s;
  for (int i = 0; i < n; ++i) {
    const double angle = 2 * M_PI * i / n;
    const Eigen::Matrix3d r = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
    s.truth.emplace_back(r, Eigen::Vector3d(std::sin(angle), 0, 1 - std::cos(angle)));
  }
  const SE3 bias = SE3::Exp((SE3::Tangent() << 0.003, 0, 0, 0, 0.004, 0).finished());
  const Matrix6d odometry_information = Isotropic(0.005, 0.005);
  s.odometry.push_back(s.truth[0]);
  s.graph.AddNode(0, s.truth[0]);
  for (int i = 1; i < n; ++i) {
    const SE3 measured =
        (s.truth[i - 1].Inverse() * s.truth[i]) * bias * RandomPose(&rng, 0.002, 0.002);
    s.odometry.push_back(s.odometry.back() * measured);
    s.graph.AddNode(i, s.odometry.back());
    s.graph.AddEdge({i - 1, i, measured, odometry_information, PoseGraphEdge::Kind::kOdometry});
  }
  const Matrix6d loop_information = Isotropic(0.003, 0.003);
  for (int k = 0; k < 3; ++k) {
    const int from = k, to = n - 3 + k;
    s.graph.AddEdge({from, to,
                     s.truth[from].Inverse() * s.truth[to] * RandomPose(&rng, 0.002, 0.002),
                     loop_information, PoseGraphEdge::Kind::kLoop});
  }
  return s;
}

double Rmse(const std::vector<SE3>& truth, const std::map<int, SE3>& poses) {
  double sum = 0;
  for (const auto& [id, pose] : poses)
    sum += (pose.translation() - truth[id].translation()).squaredNorm();
  return std::sqrt(sum / poses.size());
}

std::map<int, SE3> Indexed(const std::vector<SE3>& poses) {
  std::map<int, SE3> m;
  for (size_t i = 0; i < poses.size(); ++i) m[static_cast<int>(i)] = poses[i];
  return m;
}

TEST(PoseGraph, ClosingALoopRemovesMostOfTheDrift) {
  LoopScenario s = MakeLoop(60, 1);
  const double before = Rmse(s.truth, Indexed(s.odometry));
  const PoseGraphSummary summary = s.graph.Optimize({});
  ASSERT_TRUE(summary.success) << summary.BriefReport();
  EXPECT_EQ(summary.rejected, 0);
  const double after = Rmse(s.truth, s.graph.poses());
  EXPECT_GT(before, 0.1);                                    // the drift is real: decimetres
  EXPECT_LT(after, 0.35 * before) << summary.BriefReport();  // measured: 0.26
  // The first node is the fixed gauge.
  EXPECT_LT((s.graph.pose(0).translation() - s.truth[0].translation()).norm(), 1e-9);
}

TEST(PoseGraph, RejectsAWrongLoopAndKeepsTheRightOnes) {
  LoopScenario s = MakeLoop(60, 2);
  LoopScenario clean = MakeLoop(60, 2);
  clean.graph.Optimize({});
  // A false loop: keyframe 30 (the far side of the circle) claimed to be beside keyframe 5.
  const Matrix6d loop_information = Isotropic(0.003, 0.003);
  s.graph.AddEdge({5, 30, SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.1, 0, 0.05)),
                   loop_information, PoseGraphEdge::Kind::kLoop});
  const PoseGraphSummary summary = s.graph.Optimize({});
  ASSERT_TRUE(summary.success) << summary.BriefReport();
  EXPECT_EQ(summary.rejected, 1);
  for (const PoseGraphEdge& e : s.graph.edges())
    EXPECT_EQ(e.rejected, e.from == 5 && e.to == 30) << e.from << "-" << e.to;
  EXPECT_LT(Rmse(s.truth, s.graph.poses()), Rmse(clean.truth, clean.graph.poses()) + 0.005);
}

// Held nodes stay where they are; the solve covers only the free nodes and the edges that touch
// them, and brings those back to where the whole graph's solve put them.
TEST(PoseGraph, HeldNodesStayAndTheSolveCoversOnlyTheFreeOnes) {
  LoopScenario s = MakeLoop(60, 1);
  ASSERT_TRUE(s.graph.Optimize({}).success);
  const std::map<int, SE3> solved = s.graph.poses();
  for (int id = 1; id < 40; ++id) s.graph.Hold(id);
  std::mt19937 rng(7);
  for (int id = 40; id < 60; ++id)
    s.graph.SetPose(id, solved.at(id) * RandomPose(&rng, 0.05, 0.05));
  const PoseGraphSummary summary = s.graph.Optimize({});
  ASSERT_TRUE(summary.success) << summary.BriefReport();
  EXPECT_EQ(summary.nodes, 20);
  EXPECT_EQ(summary.held, 39);
  EXPECT_EQ(summary.edges, 20 + 3);  // odometry 39-40 ... 58-59, and the three loop edges
  for (int id = 0; id < 40; ++id)
    EXPECT_EQ(s.graph.pose(id).translation(), solved.at(id).translation()) << id;
  for (int id = 40; id < 60; ++id)
    EXPECT_LT((s.graph.pose(id).translation() - solved.at(id).translation()).norm(), 0.002) << id;
}

TEST(PoseGraph, RefusesEdgesToMissingNodes) {
  PoseGraph graph;
  graph.AddNode(0, SE3());
  EXPECT_THROW(graph.AddEdge({0, 1, SE3(), Matrix6d::Identity(), PoseGraphEdge::Kind::kLoop}),
               std::logic_error);
  PoseGraphOptions bad;
  bad.max_loop_chi2 = 0;
  EXPECT_FALSE(bad.Check());
}

TEST(PoseGraph, NodesWithinFollowMeasuredEdgesOnly) {
  PoseGraph graph;
  for (int id = 0; id < 8; ++id) graph.AddNode(id, SE3());
  using Kind = PoseGraphEdge::Kind;
  for (int id = 1; id < 6; ++id) graph.AddEdge({id - 1, id, SE3(), Matrix6d::Identity()});
  graph.AddEdge({0, 5, SE3(), Matrix6d::Identity(), Kind::kLoop});   // a loop back to the start
  graph.AddEdge({5, 6, SE3(), Matrix6d::Identity(), Kind::kGap});    // a guess: not followed
  PoseGraphEdge rejected{2, 7, SE3(), Matrix6d::Identity(), Kind::kLoop};
  rejected.rejected = true;                                          // refused: not followed
  graph.AddEdge(rejected);
  EXPECT_EQ(graph.NodesWithin(5, 0), (std::set<int>{5}));
  EXPECT_EQ(graph.NodesWithin(5, 1), (std::set<int>{0, 4, 5}));
  EXPECT_EQ(graph.NodesWithin(5, 2), (std::set<int>{0, 1, 3, 4, 5}));
  EXPECT_EQ(graph.NodesWithin(2, 8), (std::set<int>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(graph.NodesWithin(6, 3), (std::set<int>{6}));
}

}  // namespace
}  // namespace gf
