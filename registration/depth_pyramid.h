// Vertex and normal maps of a depth image at several resolutions, the input of projective ICP.
//
// Level 0 is the full image; each next level halves width and height, averaging the valid depths of
// each 2x2 block whose values agree (within 3 cm, so edges do not blend foreground and background).
// Vertices are points in the camera frame (metres), normals unit vectors facing the camera;
// invalid pixels are NaN.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "acquisition/camera.h"

namespace gf {

struct DepthPyramid {
  std::vector<Camera> cameras;    // intrinsics per level
  std::vector<cv::Mat> depth;     // CV_32FC1 metres, 0 = none
  std::vector<cv::Mat> vertices;  // CV_32FC3, point_in_camera, NaN where no depth
  std::vector<cv::Mat> normals;   // CV_32FC3, unit, NaN where undefined
  int levels() const { return static_cast<int>(depth.size()); }
};

// depth_m: CV_32FC1 metres (0 = hole) matching `camera`. levels >= 1.
DepthPyramid BuildDepthPyramid(const cv::Mat& depth_m, const Camera& camera, int levels);

}  // namespace gf
