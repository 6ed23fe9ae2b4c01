// A frame's SURF features with the 3D point under each: what tracking matches to its keyframe and
// what loop closure and relocalisation match to earlier keyframes (keyframe_database.h), computed
// once per frame.
//
// No threads, no I/O.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "registration/surf.h"

namespace gf {

struct FrameFeatures {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;                  // CV_32F, a 64-float row per keypoint
  std::vector<Eigen::Vector3d> points;  // per keypoint, camera frame (metres; lens distortion
                                        // removed); NaN where the sensor has no depth
  bool empty() const { return keypoints.empty(); }
};

// SURF on the frame's grey image and the sensor depth under each keypoint. Empty when the frame
// has no colour.
FrameFeatures ExtractFrameFeatures(const RgbdFrame& frame, const Camera& camera,
                                   const SurfOptions& surf);

}  // namespace gf
