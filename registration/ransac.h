// Feature matching and 3D-3D RANSAC: the coarse alignment that starts dense ICP.
//
// MatchDescriptors: nearest neighbour by L2 (OpenCV's brute-force matcher), kept when clearly
// better than the second (ratio test, Lowe 2004), optionally only mutual best matches, and only
// between keypoints of the same Laplacian sign (SURF's class_id; bright blob vs dark blob).
// EstimateRigidRansac: minimal samples of 3 correspondences solved in closed form (Umeyama /
// Horn), inliers within a distance threshold, the iteration count adapted to the inlier ratio for
// the requested confidence, seeded for repeatability, and a final least-squares refit on all
// inliers.
//
// No threads, no I/O.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "acquisition/se3.h"

namespace gf {

struct MatchOptions {
  double ratio = 0.8;          // best / second-best distance must be below this
  bool cross_check = false;    // keep only mutual best matches
  bool same_laplacian = true;  // only match keypoints with equal class_id (Laplacian sign)
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

// query/train descriptors: CV_32F rows; keypoints give class_id for the Laplacian check.
std::vector<cv::DMatch> MatchDescriptors(const std::vector<cv::KeyPoint>& query_keypoints,
                                         const cv::Mat& query_descriptors,
                                         const std::vector<cv::KeyPoint>& train_keypoints,
                                         const cv::Mat& train_descriptors,
                                         const MatchOptions& options);

struct RansacOptions {
  double inlier_threshold_m = 0.03;  // correspondence distance after alignment, metres
  double confidence = 0.995;         // probability of drawing one all-inlier sample
  int max_iterations = 1000;  // hypotheses; at most 1e6 (microseconds each: seconds per frame)
  int min_inliers = 10;  // fewer: failure
  uint32_t seed = 1;     // sampling is deterministic for a seed
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

struct RansacReport {
  bool success = false;
  std::string termination;  // "ok", "too few correspondences", "too few inliers"
  SE3 target_from_source;
  int iterations = 0;
  int inliers = 0;
  double inlier_ratio = 0;
  double rmse_m = 0;  // of the inliers after the refit
  std::vector<int> inlier_indices;
  std::string BriefReport() const;
};

// source[i] corresponds to target[i] (metres). Finds target_from_source.
RansacReport EstimateRigidRansac(const std::vector<Eigen::Vector3d>& source,
                                 const std::vector<Eigen::Vector3d>& target,
                                 const RansacOptions& options);

}  // namespace gf
