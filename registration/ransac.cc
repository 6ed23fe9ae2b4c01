#include "registration/ransac.h"

#include <cmath>
#include <cstdio>
#include <opencv2/features2d.hpp>
#include <random>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"
#include "acquisition/trajectory_metrics.h"

namespace gf {

bool MatchOptions::Check(std::string* message) const {
  // Distances are non-negative: best / second best is at most 1.
  FieldCheck c(message);
  c.Above("ratio", ratio, 0, 1, kMoreThanOne);
  return c.ok();
}

std::vector<cv::DMatch> MatchDescriptors(const std::vector<cv::KeyPoint>& query_keypoints,
                                         const cv::Mat& query_descriptors,
                                         const std::vector<cv::KeyPoint>& train_keypoints,
                                         const cv::Mat& train_descriptors,
                                         const MatchOptions& options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  std::vector<cv::DMatch> matches;
  if (query_descriptors.rows < 2 || train_descriptors.rows < 2) return matches;
  cv::BFMatcher matcher(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(query_descriptors, train_descriptors, knn, 2);
  std::vector<int> reverse;
  if (options.cross_check) {
    std::vector<cv::DMatch> back;
    matcher.match(train_descriptors, query_descriptors, back);
    reverse.assign(train_descriptors.rows, -1);
    for (const cv::DMatch& m : back) reverse[m.queryIdx] = m.trainIdx;
  }
  for (const auto& pair : knn) {
    if (pair.size() < 2 || pair[0].distance >= options.ratio * pair[1].distance) continue;
    const cv::DMatch& m = pair[0];
    if (options.same_laplacian &&
        query_keypoints[m.queryIdx].class_id != train_keypoints[m.trainIdx].class_id)
      continue;
    if (options.cross_check && reverse[m.trainIdx] != m.queryIdx) continue;
    matches.push_back(m);
  }
  return matches;
}

bool RansacOptions::Check(std::string* message) const {
  // A hypothesis (a 3-point fit, then a test of every correspondence) takes microseconds: a
  // million of them take seconds per frame, more than its time allows.
  constexpr int kMaxHypotheses = 1'000'000;
  FieldCheck c(message);
  c.Above("inlier_threshold_m", inlier_threshold_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("confidence", confidence, 0, 1, kMoreThanOne)
      .Require(confidence < 1, "confidence must be less than 1 (certainty needs every sample)")
      .In("max_iterations", max_iterations, 1, kMaxHypotheses,
          "is more hypotheses than a frame's time allows")
      .In("min_inliers", min_inliers, 3, kMaxImagePixels, kMoreThanAnImagesPixels);
  return c.ok();
}

std::string RansacReport::BriefReport() const {
  char buffer[160];
  std::snprintf(buffer, sizeof(buffer),
                "RANSAC %s: %d inliers (%.0f%%), %d iterations, rmse %.4f m", termination.c_str(),
                inliers, 100.0 * inlier_ratio, iterations, rmse_m);
  return buffer;
}

RansacReport EstimateRigidRansac(const std::vector<Eigen::Vector3d>& source,
                                 const std::vector<Eigen::Vector3d>& target,
                                 const RansacOptions& options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  GF_CHECK(source.size() == target.size(), "source and target must correspond one to one");
  RansacReport report;
  const int n = static_cast<int>(source.size());
  if (n < std::max(3, options.min_inliers)) {
    report.termination = "too few correspondences";
    return report;
  }
  const double threshold2 = options.inlier_threshold_m * options.inlier_threshold_m;
  auto count_inliers = [&](const SE3& t, std::vector<int>* inliers) {
    inliers->clear();
    for (int i = 0; i < n; ++i)
      if ((t * source[i] - target[i]).squaredNorm() < threshold2) inliers->push_back(i);
  };
  std::mt19937 rng(options.seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::vector<int> best, current;
  int needed = options.max_iterations;
  int it = 0;
  for (; it < needed && it < options.max_iterations; ++it) {
    int a = pick(rng), b = pick(rng), c = pick(rng);
    if (a == b || b == c || a == c) continue;
    // Skip degenerate samples: points too close together or nearly collinear.
    const Eigen::Vector3d ab = source[b] - source[a], ac = source[c] - source[a];
    if (ab.cross(ac).norm() < 1e-4 || ab.norm() < 0.01 || ac.norm() < 0.01) continue;
    const SE3 t = AlignPoints({target[a], target[b], target[c]}, {source[a], source[b], source[c]});
    count_inliers(t, &current);
    if (current.size() > best.size()) {
      best = current;
      const double w = static_cast<double>(best.size()) / n;
      const double p_fail = 1.0 - w * w * w;
      needed =
          p_fail <= 1e-12
              ? 0
              : static_cast<int>(std::ceil(std::log(1.0 - options.confidence) / std::log(p_fail)));
    }
  }
  report.iterations = it;
  if (static_cast<int>(best.size()) < options.min_inliers) {
    report.termination = "too few inliers";
    report.inliers = static_cast<int>(best.size());
    return report;
  }
  // Refit on all inliers, then recount once with the refined model.
  for (int round = 0; round < 2; ++round) {
    std::vector<Eigen::Vector3d> s, d;
    for (int i : best) {
      s.push_back(source[i]);
      d.push_back(target[i]);
    }
    report.target_from_source = AlignPoints(d, s);
    count_inliers(report.target_from_source, &current);
    if (current.size() < 3) break;
    best = current;
  }
  double sum2 = 0;
  for (int i : best) sum2 += (report.target_from_source * source[i] - target[i]).squaredNorm();
  report.inliers = static_cast<int>(best.size());
  report.inlier_ratio = static_cast<double>(best.size()) / n;
  report.rmse_m = best.empty() ? 0 : std::sqrt(sum2 / best.size());
  report.inlier_indices = best;
  report.success = report.inliers >= options.min_inliers;
  report.termination = report.success ? "ok" : "too few inliers";
  return report;
}

}  // namespace gf
