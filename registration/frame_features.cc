#include "registration/frame_features.h"

#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

namespace gf {

FrameFeatures ExtractFrameFeatures(const RgbdFrame& frame, const Camera& camera,
                                   const SurfOptions& surf) {
  FrameFeatures f;
  if (frame.color.empty()) return f;
  cv::Mat gray;
  cv::cvtColor(frame.color, gray, cv::COLOR_BGR2GRAY);
  SurfFeatures detected = DetectAndDescribeSurf(gray, surf);
  f.keypoints = std::move(detected.keypoints);
  f.descriptors = detected.descriptors;
  f.points.reserve(f.keypoints.size());
  for (const cv::KeyPoint& k : f.keypoints) {
    const int u = static_cast<int>(std::lround(k.pt.x)), v = static_cast<int>(std::lround(k.pt.y));
    const float z = (u >= 0 && v >= 0 && u < frame.depth.cols && v < frame.depth.rows)
                        ? frame.depth.at<float>(v, u)
                        : 0.f;
    f.points.push_back(z > 0 ? camera.BackProject({k.pt.x, k.pt.y}, z)
                             : Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
  }
  return f;
}

}  // namespace gf
