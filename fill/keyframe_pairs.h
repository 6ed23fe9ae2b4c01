// Choosing the stereo partner of a keyframe (the method's pair selection).
//
// For keyframe I1 the partner I2 is the keyframe as far from it as possible (longest baseline,
// most parallax) that still shares at least `min_matches` SURF matches with I1 consistent with the
// pair's relative pose refined from those matches (RefinePairPose), and only when the parallax
// suits I1's depth range: the disparity of I1's median depth at least min_median_disparity_px, that
// of its near depth (5th percentile) at most max_near_disparity_px (the stereo search range), the
// baseline at least geometry.min_baseline_m, the viewing directions at most max_rotation_deg apart, and
// (unless allow_forward, since the stereo fill plane-sweeps forward pairs) the epipole outside both
// images. The geometry is screened with the tracked poses and the chosen pair's refined pose
// reported. The next acceptable keyframe after I2 is kept as the third view (photometric check,
// and a second view for the plane sweep); for a forward pair, the acceptable keyframe farthest
// from I2, which sees what I2 cannot (spread_third_view_forward); for a sideways pair, the one
// nearest I2's mirror image through I1, which sees the edge band that I2 cannot
// (mirror_third_view_sideways). Up to max_witnesses further acceptable keyframes (by geometry,
// at their tracked poses) only witness the fill (CorroborateFill).
//
// KeyframePairScheduler decides when a keyframe is ready: candidates are the `window` keyframes
// before it and the `lookahead` keyframes after it, so a keyframe's pair is chosen once
// `lookahead` later keyframes have arrived (or at Flush(), the end of the stream).
//
// No threads, no I/O. Usage:
//   gf::KeyframePairScheduler scheduler(camera, {});
//   for (each new keyframe) for (const gf::StereoJob& job : scheduler.Add(frame,
//   world_from_camera))
//     FillHolesByStereo(job.key1->frame, job.key2->frame, camera,
//                       job.choice.partner_pose.key1_from_key2, ...);   // key2 may be null
//   for (const gf::StereoJob& job : scheduler.Flush()) ...
#pragma once

#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"
#include "registration/pair_pose.h"
#include "registration/ransac.h"
#include "registration/surf.h"
#include "fill/stereo_fill.h"

namespace gf {

struct PairSelectionOptions {
  int min_matches = 40;                // M: SURF matches the pair must share (PnP RANSAC inliers)
  int max_evaluations = 10;            // candidates matched at most per keyframe (farthest first)
  PairGeometryOptions geometry;        // least baseline; forward-pair margin (shared with the fill)
  double max_baseline_m = 0.50;        // longer ones change the view too much for block matching
  double min_median_disparity_px = 8;  // parallax at I1's median depth, pixels
  double max_near_disparity_px = 80;   // parallax at I1's near depth; keep <= the stereo search
  double max_near_disparity_sweep_px = 176;  // the same for forward pairs (the plane sweep has no
                                             // search range; this bounds how far views differ)
  bool allow_forward = true;       // forward pairs too (the stereo fill plane-sweeps them)
  double max_rotation_deg = 20.0;  // largest angle between the two viewing directions, degrees
  int window = 30;                 // earlier keyframes considered as partners
  int lookahead = 10;  // later keyframes waited for before a keyframe is paired (partners may
                       // come after it)
  // The third view of a forward pair (the plane sweep's second view): the acceptable candidate
  // farthest from the partner (true), not the next one after it in order of baseline (usually the
  // partner's neighbour, nearly the same view).
  bool spread_third_view_forward = true;
  // The third view of a sideways pair (the photometric check's view and the sweep's second view
  // after SGBM): the acceptable candidate nearest the partner's mirror image through keyframe 1
  // (true), which sees the band along keyframe 1's edge that the partner cannot; or the next one
  // after the partner in order of baseline (false), usually on the partner's side
  // (docs/experiments/2026-12-03-mirrored-third-view.md).
  bool mirror_third_view_sideways = true;
  // Further keyframes with usable parallax (farthest first), at their tracked poses, that only
  // witness the fill: where one sees the filled surface as keyframe 1 does, the fill is
  // corroborated (CorroborateFill). At most this many per keyframe.
  int max_witnesses = 4;
  SurfOptions surf = [] {
    SurfOptions s;
    s.upright = true;
    s.max_features = 500;
    return s;
  }();
  MatchOptions match;
  PoseRefinementOptions refine;
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

struct PairChoice {
  bool found = false;
  int partner = -1;  // index into the candidates
  int third = -1;    // another acceptable candidate, for the photometric check (-1 = none)
  std::vector<int> witnesses;  // further candidates with usable parallax (max_witnesses)
  int matches = 0;   // RANSAC inlier matches with the partner
  PoseRefinement partner_pose;  // key1_from_partner, refined
  PoseRefinement third_pose;    // key1_from_third, refined
  double baseline_m = 0;
  double rotation_deg = 0;
  int evaluated = 0;   // candidates whose matches were counted
  std::string reason;  // why none was found
  std::string BriefReport() const;
};

PairChoice SelectPartner(const StereoKeyframe& key1,
                         const std::vector<std::shared_ptr<const StereoKeyframe>>& candidates,
                         const Camera& camera, const PairSelectionOptions& options);

struct StereoJob {
  std::shared_ptr<const StereoKeyframe> key1;
  std::shared_ptr<const StereoKeyframe> key2;   // null: no partner (choice.reason says why)
  std::shared_ptr<const StereoKeyframe> third;  // may be null
  std::vector<std::shared_ptr<const StereoKeyframe>> witnesses;  // choice.witnesses
  PairChoice choice;  // choice.partner_pose / third_pose: the refined relative poses
  std::string error;  // non-empty when pair selection threw (choice then holds no partner)
};

class KeyframePairScheduler {
 public:
  // Throws std::logic_error when options.Check() fails.
  KeyframePairScheduler(const Camera& camera, const PairSelectionOptions& options);
  // Adds a keyframe; returns the jobs that became ready (at most one). Throws, adding nothing, when
  // the frame's features cannot be computed; a pair selection that throws gives its job an
  // `error` instead.
  std::vector<StereoJob> Add(const RgbdFrame& frame, const SE3& world_from_camera);
  // End of the stream: the jobs of the keyframes still waiting for later ones.
  std::vector<StereoJob> Flush();

 private:
  StereoJob MakeJob(size_t position) const;

  Camera camera_;
  PairSelectionOptions options_;
  std::deque<std::shared_ptr<const StereoKeyframe>> keyframes_;  // window + pending
  size_t pending_ = 0;  // keyframes at the back of keyframes_ not yet paired
  int next_id_ = 0;
};

}  // namespace gf
