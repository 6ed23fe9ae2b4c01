// Loop detection: which earlier keyframes a new keyframe sees again, verified geometrically, and
// which of those loops the pose graph may trust (ORB-SLAM2's loop closing and RTAB-Map's
// verification, on this project's SURF + RANSAC + ICP).
//
// Candidates, excluding the keyframes just before the query (tracking already links those):
//  - by appearance: the best scores in the keyframe database (keyframe_database.h);
//  - by proximity: keyframes whose current pose estimate puts the camera within proximity_m and
//    its optical axis within proximity_deg of the query's estimate (drift stays small on short
//    loops, so this finds what appearance ranks low).
// VerifyLoop aligns the query to a candidate as tracking does: SURF matches, 3D-3D RANSAC, then
// point-to-plane ICP with the RANSAC inliers as the feature term, at half resolution. A loop is
// refused when the evidence is weak or ambiguous: too few RANSAC inliers or too small a share of
// the matches, inliers on a line (no spread across the image), ICP failing, overlapping too little
// or moving far from RANSAC's pose, or ICP leaving a translation direction unconstrained (a plane
// or a textureless corridor: its standard deviation along the weakest direction above
// max_sigma_m).
// A verified loop that agrees with the current estimates (within confirm_m and confirm_deg) joins
// the graph at once: it confirms what tracking says. One that moves the query further is a
// correction of drift, or a false match that happened to verify: it joins only when
// min_consistent consecutive keyframes (allowing one in between without a loop) found loops that
// imply the same correction (ORB-SLAM2's consistency test over covisible groups, here over the
// correction itself).
//
// No threads, no I/O. Usage:
//   gf::LoopDetector detector(camera, {});
//   gf::LoopDetection d = detector.Detect(*query, query_estimate, database, estimate_of);
//   for (const gf::PoseGraphEdge& e : d.accepted) graph.AddEdge(e);
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "registration/icp.h"
#include "registration/keyframe_database.h"
#include "registration/pose_graph.h"
#include "registration/ransac.h"

namespace gf {

struct LoopVerificationOptions {
  MatchOptions match;
  RansacOptions ransac = [] {
    RansacOptions r;
    r.min_inliers = 20;  // ORB-SLAM2 asks for 20 or more
    return r;
  }();
  double min_inlier_ratio = 0.25;  // RANSAC inliers over the matches with depth on both sides
  double min_spread_m = 0.05;      // inlier points' extent along their second principal axis
  IcpOptions icp = [] {            // at half resolution (320x240 from 640x480)
    IcpOptions o;
    o.iterations = {8, 6, 4};
    o.min_inliers = 2000;
    return o;
  }();
  double min_overlap = 0.3;       // share of the query's points landing on the candidate
  double max_refine_m = 0.05;     // ICP may move RANSAC's pose by at most this, metres
  double max_refine_deg = 3.0;    // ... and degrees
  double max_sigma_m = 0.01;      // ICP's translational standard deviation, weakest direction
  // Errors the alignment's own information leaves out (depth calibration, rolling shutter,
  // correlated noise), added to its covariance for the pose graph (pose_graph.h).
  AlignmentNoise noise;
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

struct LoopVerification {
  bool success = false;
  std::string reason;  // why it was refused
  SE3 candidate_from_query;
  Matrix6d information = Matrix6d::Zero();  // with the floor (pose_graph.h's convention)
  int matches = 0, inliers = 0;
  double inlier_ratio = 0, spread_m = 0, weakest_sigma_m = 0;
  IcpSummary icp;
  std::string BriefReport() const;
};

// Aligns `query` to `candidate` (both keep half-resolution depth; `camera` is the full-size one).
LoopVerification VerifyLoop(const LoopKeyframe& query, const LoopKeyframe& candidate,
                            const Camera& camera, const LoopVerificationOptions& options);

struct LoopDetectorOptions {
  // The keyframes just before the query are no candidates, nor, where Detect() is given the
  // graph's neighbourhood, keyframes this many edges or fewer from the query in the pose graph
  // (tracking, or an earlier loop of a keyframe just before it, already ties them to it: a loop to
  // them repeats what the graph holds, and cannot correct drift that a short chain has not got).
  int recent_keyframes = 8;
  int appearance_candidates = 3;   // best appearance scores verified per keyframe
  double min_appearance_score = 0.05;  // histogram intersection, 0-1
  int proximity_candidates = 2;    // nearest by pose verified per keyframe (not already chosen)
  double proximity_m = 0.3;        // camera centres within this, metres
  double proximity_deg = 30.0;     // optical axes within this, degrees
  LoopVerificationOptions verification;
  double confirm_m = 0.02;    // a loop moving the query less than this agrees with the graph
  double confirm_deg = 1.5;   // ... and less than this, degrees
  int min_consistent = 3;     // consecutive keyframes that must imply the same larger correction
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

struct LoopCandidate {
  int id = 0;
  std::string found_by;  // "appearance" or "proximity"
  double appearance_score = 0;
  LoopVerification verification;
  // "accepted", "pending" (awaiting consistent keyframes), or why it was refused.
  std::string outcome;
};

struct LoopDetection {
  std::vector<LoopCandidate> candidates;
  std::vector<PoseGraphEdge> accepted;  // kLoop edges from candidate to query, ready for the graph
  bool consistent_correction = false;   // edges accepted that move the graph (re-optimise now)
  std::string BriefReport() const;
};

class LoopDetector {
 public:
  // Throws std::logic_error when options.Check() fails.
  LoopDetector(const Camera& camera, const LoopDetectorOptions& options);
  // `query` is not in `database` yet; estimate(id) gives the current world_from_camera estimate
  // of a database keyframe, query_estimate the query's; tied(id) (may be empty) is true for the
  // keyframes within recent_keyframes edges of the query in the pose graph (not verified).
  LoopDetection Detect(const LoopKeyframe& query, const SE3& query_estimate,
                       const KeyframeDatabase& database,
                       const std::function<SE3(int)>& estimate,
                       const std::function<bool(int)>& tied = {});

 private:
  std::vector<LoopCandidate> Candidates(const LoopKeyframe& query, const SE3& query_estimate,
                                        const KeyframeDatabase& database,
                                        const std::function<SE3(int)>& estimate,
                                        const std::function<bool(int)>& tied) const;
  // Verified loops that disagree with the graph, kept until consecutive keyframes confirm them.
  struct Pending {
    int query = -1;
    SE3 query_estimate;   // the query's estimate then
    SE3 corrected_query;  // where its loops put it
    std::vector<PoseGraphEdge> edges;
  };
  Camera camera_;
  LoopDetectorOptions options_;
  std::vector<Pending> chain_;
};

}  // namespace gf
