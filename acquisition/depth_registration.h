// Depth-to-colour registration for sources whose depth comes from a separate camera (raw Kinect v1
// disparity, unregistered OpenNI streams).
//
// Each valid depth pixel is lifted to 3D in the depth camera, moved into the colour camera by
// color_from_depth, and splatted into the colour image with a z-buffer (nearest surface wins). Each
// source pixel covers a footprint of its projected size, so no cracks appear when the colour
// camera's focal length is larger than the depth camera's. Hole pixels are carried over too, placed
// at the depth of the far side of their run (where a shadow or a glass pane's background lies),
// so the registered hole mask keeps its classes; colour pixels that no depth pixel reaches are
// marked kOutOfRange (outside the depth camera's view).
//
// Usage:
//   cv::Mat depth_c, holes_c;
//   gf::RegisterDepthToColor(frame.depth, frame.hole_mask, depth_camera, color_camera,
//                            color_from_depth, &depth_c, &holes_c);
#pragma once

#include <opencv2/core.hpp>

#include "acquisition/camera.h"
#include "acquisition/se3.h"

namespace gf {

// depth_m: CV_32FC1 metres (0 = hole) in the depth camera; hole_mask: CV_8UC1 HoleCode, same size.
// Outputs are colour-camera sized: registered_depth CV_32FC1, registered_holes CV_8UC1.
// Both cameras' lens distortion is applied (a depth pixel's ray through the depth lens, its point
// through the colour lens; the footprint is the pixel's size where it lies on the image).
void RegisterDepthToColor(const cv::Mat& depth_m, const cv::Mat& hole_mask,
                          const Camera& depth_camera, const Camera& color_camera,
                          const SE3& color_from_depth, cv::Mat* registered_depth,
                          cv::Mat* registered_holes);

}  // namespace gf
