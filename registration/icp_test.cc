#include "registration/icp.h"

#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <random>

#include "acquisition/frame_source.h"
#include "datasets/synth.h"
#include "tests/testing.h"

namespace gf {
namespace {

// Ceres wrappers: residual as a function of a left increment xi at T, with our analytic Jacobian.
class PointToPlaneCost : public ceres::SizedCostFunction<1, 6> {
 public:
  PointToPlaneCost(SE3 t, Eigen::Vector3d p, Eigen::Vector3d q, Eigen::Vector3d n)
      : t_(t), p_(p), q_(q), n_(n) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const SE3 t = SE3::Exp(Eigen::Map<const SE3::Tangent>(parameters[0])) * t_;
    Eigen::Matrix<double, 1, 6> j;
    residuals[0] = PointToPlaneResidual(t, p_, q_, n_, &j);
    // The analytic Jacobian is with respect to a further increment at t; at xi = 0 (where the
    // checker evaluates) that is the derivative with respect to xi.
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, 1, 6>> jacobian(jacobians[0]);
      jacobian = j;
    }
    return true;
  }

 private:
  SE3 t_;
  Eigen::Vector3d p_, q_, n_;
};

class ReprojectionCost : public ceres::SizedCostFunction<2, 6> {
 public:
  ReprojectionCost(SE3 t, Camera c, Eigen::Vector3d p, Eigen::Vector2d u)
      : t_(t), c_(c), p_(p), u_(u) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const SE3 t = SE3::Exp(Eigen::Map<const SE3::Tangent>(parameters[0])) * t_;
    Eigen::Matrix<double, 2, 6> j;
    Eigen::Map<Eigen::Vector2d> residual(residuals);
    residual = ReprojectionResidual(t, c_, p_, u_, &j);
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, 2, 6, Eigen::RowMajor>> jacobian(jacobians[0]);
      jacobian = j;
    }
    return true;
  }

 private:
  SE3 t_;
  Camera c_;
  Eigen::Vector3d p_;
  Eigen::Vector2d u_;
};

TEST(IcpCosts, AnalyticJacobiansPassCeresGradientChecker) {
  std::mt19937 rng(9);
  std::normal_distribution<double> g(0, 1);
  ceres::NumericDiffOptions numeric;
  double xi[6] = {0, 0, 0, 0, 0, 0};
  std::vector<double*> params = {xi};
  for (int trial = 0; trial < 20; ++trial) {
    SE3::Tangent tangent;
    tangent << 0.1 * g(rng), 0.1 * g(rng), 0.1 * g(rng), 0.2 * g(rng), 0.2 * g(rng), 0.2 * g(rng);
    const SE3 t = SE3::Exp(tangent);
    const Eigen::Vector3d p(0.3 * g(rng), 0.2 * g(rng), 2.0 + 0.3 * g(rng));
    const Eigen::Vector3d q = t * p + Eigen::Vector3d(0.01 * g(rng), 0.01 * g(rng), 0.01 * g(rng));
    const Eigen::Vector3d n = Eigen::Vector3d(g(rng), g(rng), -3).normalized();
    PointToPlaneCost plane(t, p, q, n);
    const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
    ceres::GradientChecker plane_checker(&plane, no_manifolds, numeric);
    ceres::GradientChecker::ProbeResults results;
    EXPECT_TRUE(plane_checker.Probe(params.data(), 1e-7, &results)) << results.error_log;

    ReprojectionCost reprojection(t, Camera{}, p, Eigen::Vector2d(300 + g(rng), 200 + g(rng)));
    ceres::GradientChecker reprojection_checker(&reprojection, no_manifolds, numeric);
    EXPECT_TRUE(reprojection_checker.Probe(params.data(), 1e-6, &results)) << results.error_log;
  }
}

TEST(AlignPointToPlane, RecoversTheMotionBetweenTwoSyntheticKinectFrames) {
  synth::SynthOptions options;
  options.frames = 40;
  const synth::Scene scene = synth::Scene::Make("glass-table", 2);
  const std::vector<SE3> poses = synth::MakeTrajectory(scene, options);
  const Camera camera = synth::SynthCamera();
  auto depth_of = [&](int i) {
    const synth::SynthFrame f = synth::RenderFrame(scene, camera, poses[i], options.kinect, 2, i);
    return BuildDepthPyramid(synth::ToRgbdFrame(f, i).depth, camera, 3);
  };
  const DepthPyramid ref = depth_of(10), cur = depth_of(13);
  const SE3 truth = poses[10].Inverse() * poses[13];
  // Three frames apart: about 5 cm and 2 degrees, started from identity. (Four frames, 6.5 cm,
  // is outside the dense term's basin on this orbit: that is what the feature term is for.)
  ASSERT_GT(truth.TranslationNorm(), 0.04);
  const IcpSummary s = AlignPointToPlane(ref, cur, SE3(), IcpOptions{});
  ASSERT_TRUE(s.success) << s.BriefReport();
  const SE3 error = truth.Inverse() * s.reference_from_current;
  EXPECT_LT(error.TranslationNorm(), 0.002) << s.BriefReport();
  EXPECT_LT(error.RotationAngle() * 180 / M_PI, 0.1) << s.BriefReport();
}

TEST(AlignPointToPlane, RealTumFrameRecoversAPerturbation) {
  GF_REQUIRE_DATASET(tum, "tum_fr1_xyz_head");
  FrameSourceOptions options;
  options.load_color = false;
  auto source = OpenFrameSource(tum, options);
  RgbdFrame frame;
  ASSERT_TRUE(source->Next(&frame));
  const DepthPyramid p = BuildDepthPyramid(frame.depth, source->camera(), 3);
  // Start 4 cm and 3 degrees away from the truth (identity).
  const SE3 guess = SE3::Exp((SE3::Tangent() << 0.03, -0.02, 0.015, 0.03, -0.03, 0.02).finished());
  const IcpSummary s = AlignPointToPlane(p, p, guess, IcpOptions{});
  ASSERT_TRUE(s.success) << s.BriefReport();
  EXPECT_LT(s.reference_from_current.TranslationNorm(), 0.001) << s.BriefReport();
  EXPECT_LT(s.reference_from_current.RotationAngle() * 180 / M_PI, 0.05) << s.BriefReport();
  EXPECT_LT(s.rmse_m, 0.001);
}

TEST(AlignPointToPlane, ReportsFailureWithoutOverlap) {
  cv::Mat near(480, 640, CV_32FC1, cv::Scalar(1.0f));
  cv::Mat empty(480, 640, CV_32FC1, cv::Scalar(0.0f));
  empty(cv::Rect(0, 0, 20, 20)).setTo(1.0f);
  const IcpSummary s =
      AlignPointToPlane(BuildDepthPyramid(near, Camera{}, 3), BuildDepthPyramid(empty, Camera{}, 3),
                        SE3(), IcpOptions{});
  EXPECT_FALSE(s.success);
  EXPECT_NE(s.termination.find("too few inliers"), std::string::npos) << s.termination;
}

}  // namespace
}  // namespace gf
