#include "fill/depth_candidates.h"

#include <cmath>

#include "acquisition/errors.h"

namespace gf {

RectifiedSgbmCandidates::RectifiedSgbmCandidates(SgbmRectification rect,
                                                 const SgbmOptions& options, double min_depth_m,
                                                 double max_depth_m)
    : rect_(std::move(rect)),
      options_(options),
      min_depth_m_(min_depth_m),
      max_depth_m_(max_depth_m) {
  GF_CHECK(rect_.usable, "SGBM candidates need a usable rectification: " + rect_.BriefReport());
}

cv::Mat RectifiedSgbmCandidates::Compute(const StereoPair& pair, const cv::Mat& region) const {
  // SGBM runs with the left camera of the pair first; when that is keyframe 2, its points are
  // moved into keyframe 1 with the known pose.
  const SE3 key1_from_points = rect_.swapped ? pair.key1_from_key2 : SE3();
  cv::Mat depth = cv::Mat::zeros(pair.key1.depth.size(), CV_32FC1);
  for (const Eigen::Vector3d& q : SgbmPoints(rect_, pair.key1, pair.key2, pair.camera, options_)) {
    const Eigen::Vector3d p = key1_from_points * q;
    if (p.z() < min_depth_m_ || p.z() > max_depth_m_) continue;
    const Eigen::Vector2d px = pair.camera.ProjectDistorted(p);
    const int x = static_cast<int>(std::lround(px.x())), y = static_cast<int>(std::lround(px.y()));
    if (x < 0 || y < 0 || x >= depth.cols || y >= depth.rows) continue;
    if (!region.empty() && !region.at<uint8_t>(y, x)) continue;
    float& cell = depth.at<float>(y, x);
    if (cell == 0.f || p.z() < cell) cell = static_cast<float>(p.z());  // nearest surface wins
  }
  return depth;
}

cv::Mat PlaneSweepCandidates::Compute(const StereoPair& pair, const cv::Mat& region) const {
  std::vector<SweepView> views{{&pair.key2, pair.key1_from_key2}};
  if (pair.third.frame != nullptr) views.push_back({pair.third.frame, pair.third.key1_from_key3});
  const cv::Mat everywhere =
      region.empty() ? cv::Mat(pair.key1.depth.size(), CV_8UC1, cv::Scalar(255)) : region;
  return SweepDepth(pair.key1, views, pair.camera, everywhere, pair.near_m, pair.far_m, options_)
      .depth;
}

cv::Mat DepthMapCandidates::Compute(const StereoPair& pair, const cv::Mat& region) const {
  GF_CHECK(depth_.type() == CV_32FC1 && depth_.size() == pair.key1.depth.size(),
           "a depth map candidate must be CV_32F on keyframe 1's pixels");
  cv::Mat out = depth_.clone();
  if (!region.empty()) out.setTo(0.f, region == 0);
  return out;
}

}  // namespace gf
