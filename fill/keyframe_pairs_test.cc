#include "fill/keyframe_pairs.h"

#include <gtest/gtest.h>

#include "datasets/synth.h"
#include "fill/stereo_fill.h"

namespace gf {
namespace {

class KeyframePairs : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_ = synth::Scene::Make("glass-table", 5);
    synth::SynthOptions options;
    options.frames = 30;
    poses_ = synth::MakeTrajectory(scene_, options);
  }
  RgbdFrame Frame(int i) const {
    return synth::ToRgbdFrame(synth::RenderFrame(scene_, synth::SynthCamera(), poses_[i], {}, 5, i),
                              i);
  }
  // Stereo keyframes rendered at frame 10's pose moved by each offset (metres) along its camera's
  // axis `axis` (0: x, sideways; 2: z, forward).
  std::vector<std::shared_ptr<const StereoKeyframe>> Candidates(const std::vector<double>& offsets,
                                                                int axis) const {
    const Camera camera = synth::SynthCamera();
    std::vector<std::shared_ptr<const StereoKeyframe>> candidates;
    for (size_t i = 0; i < offsets.size(); ++i) {
      const SE3 pose = Moved(offsets[i], axis);
      const RgbdFrame frame = synth::ToRgbdFrame(
          synth::RenderFrame(scene_, camera, pose, {}, 5, 40 + static_cast<int>(i)), 40 + i);
      candidates.push_back(
          MakeStereoKeyframe(1 + i, frame, pose, camera, PairSelectionOptions().surf));
    }
    return candidates;
  }
  SE3 Moved(double metres, int axis) const {
    SE3::Tangent step = SE3::Tangent::Zero();
    step(axis) = metres;
    return poses_[10] * SE3::Exp(step);
  }
  synth::Scene scene_;
  std::vector<SE3> poses_;
};

// Perturb and recover: the pair pose, started 2 cm and 1 degree off, comes back to the truth.
TEST_F(KeyframePairs, RefinesAPerturbedPairPose) {
  const Camera camera = synth::SynthCamera();
  const PairSelectionOptions options;
  const auto a = MakeStereoKeyframe(0, Frame(10), poses_[10], camera, options.surf);
  const auto b = MakeStereoKeyframe(1, Frame(16), poses_[16], camera, options.surf);
  const SE3 truth = poses_[10].Inverse() * poses_[16];
  const SE3 nudge =
      SE3::Exp((SE3::Tangent() << 0.015, -0.01, 0.008, 0.01, 0.012, -0.008).finished());
  const PoseRefinement r =
      RefinePairPose(*a, *b, camera, truth * nudge, options.match, options.refine);
  ASSERT_TRUE(r.success) << r.BriefReport();
  const SE3 error = truth.Inverse() * r.key1_from_key2;
  EXPECT_LT(error.TranslationNorm(), 0.004) << r.BriefReport();
  EXPECT_LT(error.RotationAngle() * 180 / M_PI, 0.2) << r.BriefReport();
  EXPECT_GE(r.inliers, options.refine.min_inliers);
}

// The photometric step runs the iterations it is given (OpenCV replaces iteration counts that come
// without gradient thresholds by its own): none at all leaves the feature pose as it is; the
// default iterations move it and keep it near the truth.
TEST_F(KeyframePairs, PhotometricStepRunsTheIterationsItIsGiven) {
  const Camera camera = synth::SynthCamera();
  PairSelectionOptions options;
  const auto a = MakeStereoKeyframe(0, Frame(10), poses_[10], camera, options.surf);
  const auto b = MakeStereoKeyframe(1, Frame(16), poses_[16], camera, options.surf);
  const SE3 truth = poses_[10].Inverse() * poses_[16];
  options.refine.photometric = false;
  const PoseRefinement features = RefinePairPose(*a, *b, camera, truth, options.match,
                                                 options.refine);
  ASSERT_TRUE(features.success) << features.BriefReport();
  options.refine.photometric_iterations = {0, 0, 0, 0};
  PoseRefinement none = features;
  AddPhotometricStep(*a, *b, camera, truth, options.refine, &none);
  EXPECT_LT((features.key1_from_key2.Inverse() * none.key1_from_key2).TranslationNorm(), 1e-9);
  options.refine.photometric_iterations = PoseRefinementOptions().photometric_iterations;
  PoseRefinement dense = features;
  AddPhotometricStep(*a, *b, camera, truth, options.refine, &dense);
  EXPECT_GT((features.key1_from_key2.Inverse() * dense.key1_from_key2).TranslationNorm(), 1e-6);
  EXPECT_LT((truth.Inverse() * dense.key1_from_key2).TranslationNorm(), 0.004);
  options.refine.photometric_iterations = {};
  EXPECT_FALSE(options.Check());
}

// Keyframes every third frame: each keyframe gets the farthest partner that still matches, with
// the parallax limits respected, and the jobs come out in order once `lookahead` later keyframes
// have arrived (the rest at Flush()).
TEST_F(KeyframePairs, SchedulerPairsEveryKeyframeWithinTheLimits) {
  const Camera camera = synth::SynthCamera();
  PairSelectionOptions options;
  options.lookahead = 2;
  KeyframePairScheduler scheduler(camera, options);
  std::vector<StereoJob> jobs;
  const std::vector<int> frames = {0, 3, 6, 9, 12, 15, 18};
  for (int i : frames) {
    const std::vector<StereoJob> ready = scheduler.Add(Frame(i), poses_[i]);
    EXPECT_LE(ready.size(), 1u);
    jobs.insert(jobs.end(), ready.begin(), ready.end());
  }
  EXPECT_EQ(jobs.size(), frames.size() - options.lookahead);
  for (const StereoJob& job : scheduler.Flush()) jobs.push_back(job);
  ASSERT_EQ(jobs.size(), frames.size());
  int paired = 0;
  for (size_t j = 0; j < jobs.size(); ++j) {
    EXPECT_EQ(jobs[j].key1->id, static_cast<int>(j));
    if (!jobs[j].key2) continue;
    ++paired;
    const PairChoice& c = jobs[j].choice;
    EXPECT_GE(c.matches, options.min_matches);
    EXPECT_GE(c.baseline_m, options.geometry.min_baseline_m * 0.9);
    EXPECT_LE(c.baseline_m, options.max_baseline_m);
    EXPECT_LE(c.rotation_deg, options.max_rotation_deg + 1);
    EXPECT_NE(jobs[j].key2->id, jobs[j].key1->id);
    if (jobs[j].third) {
      EXPECT_NE(jobs[j].third->id, jobs[j].key2->id);
    }
    // The chosen pair's pose was refined, and lies within 5 mm of the truth.
    EXPECT_TRUE(c.partner_pose.success) << c.partner_pose.BriefReport();
    const SE3 truth = poses_[frames[j]].Inverse() * poses_[frames[jobs[j].key2->id]];
    EXPECT_LT((truth.Inverse() * c.partner_pose.key1_from_key2).TranslationNorm(), 0.005);
  }
  EXPECT_GE(paired, static_cast<int>(frames.size()) - 1);
}

// Forward motion along the optical axis: the partner is the farthest keyframe behind; the third
// view is the one in front (the farthest from the partner, with spread_third_view_forward), not
// the partner's neighbour behind, which is what it gets without.
TEST_F(KeyframePairs, ForwardPairGetsAThirdViewFarFromThePartner) {
  const Camera camera = synth::SynthCamera();
  PairSelectionOptions options;
  const auto key1 = MakeStereoKeyframe(0, Frame(10), poses_[10], camera, options.surf);
  const auto candidates = Candidates({-0.16, -0.12, -0.08, 0.06}, 2);
  ASSERT_TRUE(IsForwardPair(camera, poses_[10].Inverse() * Moved(-0.16, 2),
                            options.geometry.epipole_margin_px));
  const PairChoice spread = SelectPartner(*key1, candidates, camera, options);
  ASSERT_TRUE(spread.found) << spread.reason;
  EXPECT_EQ(spread.partner, 0) << spread.BriefReport();
  EXPECT_EQ(spread.third, 3) << spread.BriefReport();
  EXPECT_TRUE(spread.third_pose.success) << spread.third_pose.BriefReport();

  options.spread_third_view_forward = false;
  const PairChoice next = SelectPartner(*key1, candidates, camera, options);
  ASSERT_TRUE(next.found) << next.reason;
  EXPECT_EQ(next.partner, 0);
  EXPECT_EQ(next.third, 1);
}

// Sideways motion along the camera's x axis, two candidates on either side: the partner is the
// farthest; with mirror_third_view_sideways the third view is the one nearest the partner's mirror
// image (on the other side, seeing the edge band the partner cannot), without it the next one in
// order of baseline (the partner's neighbour).
TEST_F(KeyframePairs, SidewaysPairCanGetAThirdViewOppositeThePartner) {
  const Camera camera = synth::SynthCamera();
  PairSelectionOptions options;
  const auto key1 = MakeStereoKeyframe(0, Frame(10), poses_[10], camera, options.surf);
  const auto candidates = Candidates({-0.10, -0.09, 0.08, 0.05}, 0);
  ASSERT_FALSE(IsForwardPair(camera, poses_[10].Inverse() * Moved(-0.10, 0),
                             options.geometry.epipole_margin_px));
  options.mirror_third_view_sideways = false;
  const PairChoice next = SelectPartner(*key1, candidates, camera, options);
  ASSERT_TRUE(next.found) << next.reason;
  EXPECT_EQ(next.partner, 0) << next.BriefReport();
  EXPECT_EQ(next.third, 1) << next.BriefReport();

  options.mirror_third_view_sideways = true;
  const PairChoice mirrored = SelectPartner(*key1, candidates, camera, options);
  ASSERT_TRUE(mirrored.found) << mirrored.reason;
  EXPECT_EQ(mirrored.partner, 0);
  EXPECT_EQ(mirrored.third, 2) << mirrored.BriefReport();
  EXPECT_TRUE(mirrored.third_pose.success) << mirrored.third_pose.BriefReport();
}

TEST(PairSelectionOptions, RejectsBadSettings) {
  PairSelectionOptions o;
  EXPECT_TRUE(o.Check());
  o.max_baseline_m = o.geometry.min_baseline_m / 2;
  std::string message;
  EXPECT_FALSE(o.Check(&message));
  EXPECT_FALSE(message.empty());
}

}  // namespace
}  // namespace gf
