#include "registration/loop_detector.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"
#include "registration/depth_pyramid.h"

namespace gf {
namespace {

constexpr double kDegPerRad = 180.0 / M_PI;

std::string Format(const char* format, double a, double b = 0) {
  char buffer[160];
  std::snprintf(buffer, sizeof(buffer), format, a, b);
  return buffer;
}

// True when `a` and `b` differ by less than metres and degrees.
bool Close(const SE3& a, const SE3& b, double metres, double degrees) {
  const SE3 d = a.Inverse() * b;
  return d.TranslationNorm() < metres && d.RotationAngle() * kDegPerRad < degrees;
}

// The half-resolution depth of a loop keyframe as a pyramid for ICP.
DepthPyramid HalfPyramid(const LoopKeyframe& k, const Camera& camera, int levels) {
  cv::Mat metres;
  k.depth.convertTo(metres, CV_32F, 0.001);
  Camera half = camera.Scaled(0.5);
  half.width = metres.cols;
  half.height = metres.rows;
  return BuildDepthPyramid(metres, half, levels);
}

// Extent of points along their second principal axis (standard deviation, metres): small when
// they lie on a line.
double SecondSpread(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 3) return 0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= points.size();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const auto& p : points) covariance += (p - mean) * (p - mean).transpose();
  covariance /= points.size();
  const Eigen::Vector3d eigenvalues =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvalues();  // ascending
  return std::sqrt(std::max(0.0, eigenvalues(1)));
}

// Standard deviation of the translation along its least constrained direction, metres (the
// rotation marginalised), from an alignment's information.
double WeakestTranslationSigma(const Matrix6d& information) {
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eigen(information);
  if (!(eigen.eigenvalues()(0) > 1e-9 * std::max(1.0, eigen.eigenvalues()(5)))) return 1e3;
  const Matrix6d covariance = eigen.eigenvectors() * eigen.eigenvalues().cwiseInverse().asDiagonal() *
                              eigen.eigenvectors().transpose();
  const Eigen::Vector3d translational =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance.topLeftCorner<3, 3>())
          .eigenvalues();
  return std::sqrt(std::max(0.0, translational(2)));
}

}  // namespace

bool LoopVerificationOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.In("min_inlier_ratio", min_inlier_ratio, 0, 1, kMoreThanOne)
      .In("min_spread_m", min_spread_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .In("min_overlap", min_overlap, 0, 1, kMoreThanOne)
      .Above("max_refine_m", max_refine_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("max_refine_deg", max_refine_deg, 0, kMaxAngleDeg, kMoreThanAHalfTurn)
      .Above("max_sigma_m", max_sigma_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Part("noise", noise)
      .Part("match", match)
      .Part("ransac", ransac)
      .Part("icp", icp);
  return c.ok();
}

std::string LoopVerification::BriefReport() const {
  char buffer[240];
  std::snprintf(buffer, sizeof(buffer),
                "%s: %d/%d RANSAC inliers (%.0f%%), spread %.3f m, ICP %s, overlap %d/%d, "
                "weakest sigma %.4f m",
                success ? "verified" : reason.c_str(), inliers, matches, 100 * inlier_ratio,
                spread_m, icp.success ? "ok" : icp.termination.c_str(), icp.overlapping_points,
                icp.valid_points, weakest_sigma_m);
  return buffer;
}

LoopVerification VerifyLoop(const LoopKeyframe& query, const LoopKeyframe& candidate,
                            const Camera& camera, const LoopVerificationOptions& options) {
  LoopVerification v;
  const FrameFeatures& fq = *query.features;
  const FrameFeatures& fc = *candidate.features;
  if (fq.empty() || fc.empty()) {
    v.reason = "no features";
    return v;
  }
  const std::vector<cv::DMatch> matches = MatchDescriptors(
      fq.keypoints, fq.descriptors, fc.keypoints, fc.descriptors, options.match);
  std::vector<Eigen::Vector3d> source, target;
  std::vector<cv::Point2f> target_pixels;
  for (const cv::DMatch& m : matches) {
    if (!fq.points[m.queryIdx].allFinite() || !fc.points[m.trainIdx].allFinite()) continue;
    source.push_back(fq.points[m.queryIdx]);
    target.push_back(fc.points[m.trainIdx]);
    target_pixels.push_back(fc.keypoints[m.trainIdx].pt);
  }
  v.matches = static_cast<int>(source.size());
  const RansacReport ransac = EstimateRigidRansac(source, target, options.ransac);
  v.inliers = ransac.inliers;
  v.inlier_ratio = v.matches ? static_cast<double>(ransac.inliers) / v.matches : 0.0;
  if (!ransac.success) {
    v.reason = Format("too few RANSAC inliers (%.0f of %.0f needed)", ransac.inliers,
                      options.ransac.min_inliers);
    return v;
  }
  if (v.inlier_ratio < options.min_inlier_ratio) {
    v.reason = Format("ambiguous: %.0f%% of the matches agree", 100 * v.inlier_ratio);
    return v;
  }
  std::vector<Eigen::Vector3d> inlier_points;
  std::vector<FeatureCorrespondence> correspondences;
  for (int i : ransac.inlier_indices) {
    inlier_points.push_back(target[i]);
    // Pixels at half resolution (pixel centres scale about the corner).
    const cv::Point2f& p = target_pixels[i];
    correspondences.push_back({source[i], Eigen::Vector2d((p.x + 0.5) * 0.5 - 0.5,
                                                          (p.y + 0.5) * 0.5 - 0.5)});
  }
  v.spread_m = SecondSpread(inlier_points);
  if (v.spread_m < options.min_spread_m) {
    v.reason = Format("degenerate: the inliers lie on a line (%.3f m across)", v.spread_m);
    return v;
  }
  const int levels = static_cast<int>(options.icp.iterations.size());
  v.icp = AlignPointToPlane(HalfPyramid(candidate, camera, levels),
                            HalfPyramid(query, camera, levels), ransac.target_from_source,
                            options.icp, correspondences);
  const double overlap =
      v.icp.valid_points ? static_cast<double>(v.icp.overlapping_points) / v.icp.valid_points : 0;
  const SE3 refine = ransac.target_from_source.Inverse() * v.icp.reference_from_current;
  v.weakest_sigma_m = WeakestTranslationSigma(v.icp.information);
  if (!v.icp.success) {
    v.reason = "ICP failed: " + v.icp.termination;
  } else if (overlap < options.min_overlap) {
    v.reason = Format("too little overlap (%.0f%%)", 100 * overlap);
  } else if (refine.TranslationNorm() > options.max_refine_m ||
             refine.RotationAngle() * kDegPerRad > options.max_refine_deg) {
    v.reason = Format("ICP moved RANSAC's pose by %.3f m, %.1f deg", refine.TranslationNorm(),
                      refine.RotationAngle() * kDegPerRad);
  } else if (v.weakest_sigma_m > options.max_sigma_m) {
    v.reason = Format("degenerate geometry: translation unconstrained to %.3f m", v.weakest_sigma_m);
  } else {
    v.success = true;
    v.candidate_from_query = v.icp.reference_from_current;
    v.information = AlignmentInformation(v.icp.information, v.candidate_from_query,
                                         query.median_depth_m, options.noise);
  }
  return v;
}

bool LoopDetectorOptions::Check(std::string* message) const {
  // Counts of keyframes (candidates, the recent ones, consistent ones) are bounded by a capture's.
  FieldCheck c(message);
  c.In("recent_keyframes", recent_keyframes, 0, kMaxCaptureFrames, kMoreFramesThanACapture)
      .In("appearance_candidates", appearance_candidates, 0, kMaxCaptureFrames,
          kMoreFramesThanACapture)
      // Histogram intersection of normalised histograms: 0-1.
      .In("min_appearance_score", min_appearance_score, 0, 1, kMoreThanOne)
      .In("proximity_candidates", proximity_candidates, 0, kMaxCaptureFrames,
          kMoreFramesThanACapture)
      .Above("proximity_m", proximity_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("proximity_deg", proximity_deg, 0, kMaxAngleDeg, kMoreThanAHalfTurn)
      .Above("confirm_m", confirm_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("confirm_deg", confirm_deg, 0, kMaxAngleDeg, kMoreThanAHalfTurn)
      .In("min_consistent", min_consistent, 1, kMaxCaptureFrames, kMoreFramesThanACapture)
      .Part("verification", verification);
  return c.ok();
}

std::string LoopDetection::BriefReport() const {
  int verified = 0, pending = 0;
  for (const LoopCandidate& c : candidates) {
    verified += c.verification.success;
    pending += c.outcome == "pending";
  }
  char buffer[160];
  std::snprintf(buffer, sizeof(buffer), "%zu loop candidates, %d verified, %zu accepted%s, %d pending",
                candidates.size(), verified, accepted.size(),
                consistent_correction ? " (a correction)" : "", pending);
  return buffer;
}

LoopDetector::LoopDetector(const Camera& camera, const LoopDetectorOptions& options)
    : camera_(camera), options_(options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
}

std::vector<LoopCandidate> LoopDetector::Candidates(
    const LoopKeyframe& query, const SE3& query_estimate, const KeyframeDatabase& database,
    const std::function<SE3(int)>& estimate, const std::function<bool(int)>& tied) const {
  const int newest_allowed = query.id - options_.recent_keyframes - 1;
  const auto allowed = [&](int id) { return id <= newest_allowed && !(tied && tied(id)); };
  std::vector<LoopCandidate> out;
  auto chosen = [&](int id) {
    return std::any_of(out.begin(), out.end(), [&](const LoopCandidate& c) { return c.id == id; });
  };
  for (const KeyframeDatabase::Match& m :
       database.QueryAppearance(query.features->descriptors, options_.appearance_candidates,
                                allowed))
    if (m.score >= options_.min_appearance_score)
      out.push_back({m.id, "appearance", m.score, {}, ""});
  std::vector<std::pair<double, int>> near;
  const Eigen::Vector3d axis = query_estimate.RotationMatrix().col(2);
  for (const auto& k : database.keyframes()) {
    if (!allowed(k->id) || chosen(k->id)) continue;
    const SE3 e = estimate(k->id);
    const double distance = (e.translation() - query_estimate.translation()).norm();
    const double angle =
        std::acos(std::clamp(e.RotationMatrix().col(2).dot(axis), -1.0, 1.0)) * kDegPerRad;
    if (distance < options_.proximity_m && angle < options_.proximity_deg)
      near.emplace_back(distance, k->id);
  }
  std::sort(near.begin(), near.end());
  for (size_t i = 0; i < near.size() && static_cast<int>(i) < options_.proximity_candidates; ++i)
    out.push_back({near[i].second, "proximity", 0.0, {}, ""});
  return out;
}

LoopDetection LoopDetector::Detect(const LoopKeyframe& query, const SE3& query_estimate,
                                   const KeyframeDatabase& database,
                                   const std::function<SE3(int)>& estimate,
                                   const std::function<bool(int)>& tied) {
  LoopDetection d;
  d.candidates = Candidates(query, query_estimate, database, estimate, tied);
  struct Disagreeing {
    LoopCandidate* candidate;
    PoseGraphEdge edge;
    SE3 corrected_query;
  };
  std::vector<Disagreeing> disagreeing;
  for (LoopCandidate& c : d.candidates) {
    c.verification = VerifyLoop(query, *database.Find(c.id), camera_, options_.verification);
    if (!c.verification.success) {
      c.outcome = c.verification.reason;
      continue;
    }
    const PoseGraphEdge edge{c.id, query.id, c.verification.candidate_from_query,
                             c.verification.information, PoseGraphEdge::Kind::kLoop};
    const SE3 corrected = estimate(c.id) * edge.from_from_to;  // where the loop puts the query
    if (Close(query_estimate, corrected, options_.confirm_m, options_.confirm_deg)) {
      c.outcome = "accepted";
      d.accepted.push_back(edge);
    } else {
      c.outcome = "pending";
      disagreeing.push_back({&c, edge, corrected});
    }
  }
  // Consecutive keyframes (one may be skipped) whose loops imply the same correction.
  const bool continues = !chain_.empty() && query.id - chain_.back().query <= 2;
  if (disagreeing.empty()) {
    if (!continues) chain_.clear();
    return d;
  }
  // This keyframe's correction: its best supported loop's, joined by its loops that agree.
  const Disagreeing& best = *std::max_element(
      disagreeing.begin(), disagreeing.end(), [](const Disagreeing& a, const Disagreeing& b) {
        return a.candidate->verification.inliers < b.candidate->verification.inliers;
      });
  Pending pending{query.id, query_estimate, best.corrected_query, {}};
  for (const Disagreeing& x : disagreeing) {
    if (Close(x.corrected_query, best.corrected_query, options_.confirm_m, options_.confirm_deg)) {
      pending.edges.push_back(x.edge);
    } else {
      x.candidate->outcome = "refused: disagrees with this keyframe's other loops";
    }
  }
  // The previous keyframe's correction, carried to this query, must put it in the same place.
  if (continues) {
    const Pending& last = chain_.back();
    const SE3 carried = last.corrected_query * last.query_estimate.Inverse() * query_estimate;
    if (!Close(carried, pending.corrected_query, options_.confirm_m, options_.confirm_deg))
      chain_.clear();
  } else {
    chain_.clear();
  }
  chain_.push_back(std::move(pending));
  if (static_cast<int>(chain_.size()) < options_.min_consistent) return d;
  for (const Pending& p : chain_) d.accepted.insert(d.accepted.end(), p.edges.begin(), p.edges.end());
  for (LoopCandidate& c : d.candidates)
    if (c.outcome == "pending") c.outcome = "accepted";
  d.consistent_correction = true;
  chain_.clear();
  return d;
}

}  // namespace gf
