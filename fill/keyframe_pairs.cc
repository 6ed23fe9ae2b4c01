#include "fill/keyframe_pairs.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include "acquisition/bounds.h"
#include "acquisition/depth.h"
#include "acquisition/errors.h"
#include "fill/stereo_fill.h"

namespace gf {
namespace {

constexpr double kDegPerRad = 180.0 / M_PI;

}  // namespace

bool PairSelectionOptions::Check(std::string* message) const {
  // Candidates, the window and the keyframes waited for are keyframes held in memory.
  FieldCheck c(message);
  c.In("min_matches", min_matches, 1, kMaxImagePixels, kMoreThanAnImagesPixels)
      .In("max_evaluations", max_evaluations, 1, kMaxFramesInMemory, kMoreFramesThanMemory)
      .In("max_witnesses", max_witnesses, 0, kMaxFramesInMemory, kMoreFramesThanMemory)
      .Part("geometry", geometry)
      .In("max_baseline_m", max_baseline_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Require(max_baseline_m > geometry.min_baseline_m,
               "max_baseline_m must be more than geometry.min_baseline_m")
      .Above("max_rotation_deg", max_rotation_deg, 0, kMaxAngleDeg, kMoreThanAHalfTurn)
      .In("min_median_disparity_px", min_median_disparity_px, 0, kMaxImageSidePx,
          kLargerThanAnyImage)
      .In("max_near_disparity_px", max_near_disparity_px, 0, kMaxImageSidePx, kLargerThanAnyImage)
      .In("max_near_disparity_sweep_px", max_near_disparity_sweep_px, 0, kMaxImageSidePx,
          kLargerThanAnyImage)
      .Require(max_near_disparity_px > min_median_disparity_px &&
                   max_near_disparity_sweep_px > min_median_disparity_px,
               "max_near_disparity_px and max_near_disparity_sweep_px must be more than "
               "min_median_disparity_px")
      .In("window", window, 1, kMaxFramesInMemory, kMoreFramesThanMemory)
      .In("lookahead", lookahead, 0, kMaxFramesInMemory, kMoreFramesThanMemory)
      .Part("surf", surf)
      .Part("match", match)
      .Part("refine", refine);
  return c.ok();
}

std::string PairChoice::BriefReport() const {
  char buffer[200];
  if (!found) {
    std::snprintf(buffer, sizeof(buffer), "no stereo partner: %s (%d candidates matched)",
                  reason.c_str(), evaluated);
  } else {
    std::snprintf(buffer, sizeof(buffer),
                  "partner %d: baseline %.3f m, rotation %.1f deg, %d RANSAC inlier matches%s",
                  partner, baseline_m, rotation_deg, matches, third >= 0 ? ", third view" : "");
  }
  return buffer;
}

namespace {

// A candidate's geometry relative to key1.
struct CandidateGeometry {
  int index;
  double baseline, rotation_deg;
  bool forward;
};

// The candidates whose parallax, baseline and rotation suit stereo with key1 (farthest first),
// and how many of the others failed which test.
struct ScreenedCandidates {
  std::vector<CandidateGeometry> in_range;
  int too_short = 0, too_long = 0, too_rotated = 0, forward = 0;
};

ScreenedCandidates ScreenCandidates(
    const StereoKeyframe& key1,
    const std::vector<std::shared_ptr<const StereoKeyframe>>& candidates, const Camera& camera,
    const PairSelectionOptions& options, double median_depth, double near_depth) {
  ScreenedCandidates screened;
  const double f = 0.5 * (camera.fx + camera.fy);
  for (size_t i = 0; i < candidates.size(); ++i) {
    const SE3 rel = key1.world_from_camera.Inverse() * candidates[i]->world_from_camera;
    const bool is_forward = IsForwardPair(camera, rel, options.geometry.epipole_margin_px);
    const CandidateGeometry g{static_cast<int>(i), rel.TranslationNorm(),
                              rel.RotationAngle() * kDegPerRad, is_forward};
    // Parallax comes from the motion across key1's optical axis, or from all of it when forward
    // pairs go to the plane sweep.
    const double lateral = options.allow_forward ? g.baseline : rel.translation().head<2>().norm();
    // Rectified stereo searches a fixed disparity range; the plane sweep (forward pairs) does not.
    const double max_near_disparity =
        is_forward ? options.max_near_disparity_sweep_px : options.max_near_disparity_px;
    if (g.baseline < options.geometry.min_baseline_m ||
        f * lateral / median_depth < options.min_median_disparity_px) {
      ++screened.too_short;
    } else if (g.baseline > options.max_baseline_m ||
               f * lateral / near_depth > max_near_disparity) {
      ++screened.too_long;
    } else if (g.rotation_deg > options.max_rotation_deg) {
      ++screened.too_rotated;
    } else if (!options.allow_forward && is_forward) {
      ++screened.forward;
    } else {
      screened.in_range.push_back(g);
    }
  }
  std::sort(screened.in_range.begin(), screened.in_range.end(),
            [](const CandidateGeometry& a, const CandidateGeometry& b) {
              return a.baseline > b.baseline;
            });
  return screened;
}

// Re-orders [first, last) by the candidates' distance from `point` (world frame, metres): the
// farthest first, or the nearest.
void OrderByDistance(const std::vector<std::shared_ptr<const StereoKeyframe>>& candidates,
                     const Eigen::Vector3d& point, bool farthest_first,
                     std::vector<CandidateGeometry>::iterator first,
                     std::vector<CandidateGeometry>::iterator last) {
  const auto distance = [&](const CandidateGeometry& c) {
    return (candidates[c.index]->world_from_camera.translation() - point).norm();
  };
  std::sort(first, last, [&](const CandidateGeometry& a, const CandidateGeometry& b) {
    return farthest_first ? distance(a) > distance(b) : distance(a) < distance(b);
  });
}

// Refines each screened candidate's pose in turn (farthest first): the first with enough matches
// is the partner, the next the third view (the rest re-ordered first: for a forward partner with
// spread_third_view_forward, farthest from the partner first; for a sideways one with
// mirror_third_view_sideways, nearest its mirror image through key1 first). Returns the most
// inliers among the candidates that fell short.
int ChoosePartnerAndThird(const StereoKeyframe& key1,
                          const std::vector<std::shared_ptr<const StereoKeyframe>>& candidates,
                          const Camera& camera, const PairSelectionOptions& options,
                          std::vector<CandidateGeometry> in_range, PairChoice* choice) {
  // The tracked relative pose can be a few centimetres off; each candidate's pose is refined
  // (PnP on the matches) and its RANSAC inliers count as the pair's matches.
  int fewest_short = 0;
  const SE3 key1_from_world = key1.world_from_camera.Inverse();
  PoseRefinementOptions features_only = options.refine;
  features_only.photometric = false;  // dense alignment only for the chosen views, below
  for (size_t n = 0; n < in_range.size(); ++n) {
    if (choice->evaluated >= options.max_evaluations) break;
    const CandidateGeometry g = in_range[n];
    const PoseRefinement pose = RefinePairPose(
        key1, *candidates[g.index], camera,
        key1_from_world * candidates[g.index]->world_from_camera, options.match, features_only);
    ++choice->evaluated;
    if (!pose.success || pose.inliers < options.min_matches) {
      fewest_short = std::max(fewest_short, pose.inliers);
      continue;
    }
    if (choice->found) {
      choice->third = g.index;
      choice->third_pose = pose;
      break;
    }
    choice->found = true;
    choice->partner = g.index;
    choice->matches = pose.inliers;
    choice->baseline_m = pose.key1_from_key2.TranslationNorm();
    choice->rotation_deg = pose.key1_from_key2.RotationAngle() * kDegPerRad;
    choice->partner_pose = pose;
    // The order in which the remaining candidates are tried as the third view (see the options).
    const Eigen::Vector3d partner_at = candidates[g.index]->world_from_camera.translation();
    if (g.forward && options.spread_third_view_forward)
      OrderByDistance(candidates, partner_at, true, in_range.begin() + n + 1, in_range.end());
    else if (!g.forward && options.mirror_third_view_sideways)
      OrderByDistance(candidates, 2 * key1.world_from_camera.translation() - partner_at, false,
                      in_range.begin() + n + 1, in_range.end());
  }
  return fewest_short;
}

}  // namespace

PairChoice SelectPartner(const StereoKeyframe& key1,
                         const std::vector<std::shared_ptr<const StereoKeyframe>>& candidates,
                         const Camera& camera, const PairSelectionOptions& options) {
  PairChoice choice;
  // Key1's depth range (median and 5th percentile of its measured depth).
  const std::vector<float> depths = SortedDepthSample(key1.frame.depth, 4);
  if (depths.size() < 100) {
    choice.reason = "keyframe has almost no measured depth";
    return choice;
  }
  const double median_depth = depths[depths.size() / 2], near_depth = depths[depths.size() / 20];
  const ScreenedCandidates screened =
      ScreenCandidates(key1, candidates, camera, options, median_depth, near_depth);
  const int fewest_short =
      ChoosePartnerAndThird(key1, candidates, camera, options, screened.in_range, &choice);
  for (const CandidateGeometry& g : screened.in_range) {
    if (static_cast<int>(choice.witnesses.size()) >= options.max_witnesses) break;
    if (choice.found && g.index != choice.partner && g.index != choice.third)
      choice.witnesses.push_back(g.index);
  }
  const SE3 key1_from_world = key1.world_from_camera.Inverse();
  if (options.refine.photometric) {
    if (choice.found)
      AddPhotometricStep(key1, *candidates[choice.partner], camera,
                         key1_from_world * candidates[choice.partner]->world_from_camera,
                         options.refine, &choice.partner_pose);
    if (choice.third >= 0)
      AddPhotometricStep(key1, *candidates[choice.third], camera,
                         key1_from_world * candidates[choice.third]->world_from_camera,
                         options.refine, &choice.third_pose);
  }
  if (!choice.found) {
    char buffer[200];
    if (screened.in_range.empty()) {
      std::snprintf(buffer, sizeof(buffer),
                    "no keyframe with usable parallax (%d too close, %d too far, %d rotated too "
                    "much, %d forward motion)",
                    screened.too_short, screened.too_long, screened.too_rotated, screened.forward);
    } else {
      std::snprintf(buffer, sizeof(buffer),
                    "too few matches (best %d RANSAC inliers of %d needed, %d candidates)",
                    fewest_short, options.min_matches, choice.evaluated);
    }
    choice.reason = buffer;
  }
  return choice;
}

KeyframePairScheduler::KeyframePairScheduler(const Camera& camera,
                                             const PairSelectionOptions& options)
    : camera_(camera), options_(options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
}

StereoJob KeyframePairScheduler::MakeJob(size_t position) const {
  StereoJob job;
  job.key1 = keyframes_[position];
  std::vector<std::shared_ptr<const StereoKeyframe>> candidates;
  for (size_t i = 0; i < keyframes_.size(); ++i)
    if (i != position) candidates.push_back(keyframes_[i]);
  try {
    job.choice = SelectPartner(*job.key1, candidates, camera_, options_);
  } catch (const std::exception& e) {
    // One keyframe's failure must not stall the stream: the job goes out without a partner.
    job.error = std::string("pair selection failed: ") + e.what();
    job.choice = PairChoice();
    job.choice.reason = job.error;
    return job;
  }
  if (job.choice.found) job.key2 = candidates[job.choice.partner];
  if (job.choice.third >= 0) job.third = candidates[job.choice.third];
  for (int w : job.choice.witnesses) job.witnesses.push_back(candidates[w]);
  return job;
}

std::vector<StereoJob> KeyframePairScheduler::Add(const RgbdFrame& frame,
                                                  const SE3& world_from_camera) {
  keyframes_.push_back(
      MakeStereoKeyframe(next_id_++, frame, world_from_camera, camera_, options_.surf));
  ++pending_;
  std::vector<StereoJob> jobs;
  if (pending_ > static_cast<size_t>(options_.lookahead)) {
    // The oldest pending keyframe now has `lookahead` later ones.
    jobs.push_back(MakeJob(keyframes_.size() - pending_));
    --pending_;
  }
  // Keep `window` paired keyframes before the pending ones.
  while (keyframes_.size() > pending_ + static_cast<size_t>(options_.window))
    keyframes_.pop_front();
  return jobs;
}

std::vector<StereoJob> KeyframePairScheduler::Flush() {
  std::vector<StereoJob> jobs;
  for (; pending_ > 0; --pending_) jobs.push_back(MakeJob(keyframes_.size() - pending_));
  return jobs;
}

}  // namespace gf
