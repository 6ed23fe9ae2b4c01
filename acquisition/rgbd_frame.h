// One RGB-D frame after conversion at the acquisition edge.
//
// Every source delivers the same thing: colour as 8-bit BGR, depth in metres (0 = no depth) and a
// hole mask that says why a pixel has no depth. Depth is registered to colour when the source's
// camera says so (RgbdFrame::depth pixel (u,v) sees the same point as color pixel (u,v)).
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "acquisition/depth.h"

namespace gf {

struct RgbdFrame {
  int index = -1;              // 0-based position in the source
  double timestamp = 0;        // depth frame time, seconds (frame index where the input has none)
  std::string timestamp_text;  // the depth timestamp exactly as the input lists it; names outputs
  double color_timestamp = 0;  // time of the associated colour image, seconds
  cv::Mat color;               // CV_8UC3, BGR; may be empty when the source was told to skip colour
  cv::Mat depth;               // CV_32FC1, metres along the optical axis, 0 = no depth
  cv::Mat hole_mask;           // CV_8UC1, gf::HoleCode per pixel
  // Holes counted in the sensor's own depth image, before registration to colour (which adds
  // pixels outside the depth camera's view); equal to CountHoles(hole_mask) for registered input.
  HoleStats sensor_holes;
  // MedianReturnDepth of the sensor's depth image (metres, before range limits); 0 when it has no
  // returns or the source does not know it (in-memory frames).
  double median_return_m = 0;
  std::string color_path;  // where the colour came from, for error messages (may be empty)
  std::string depth_path;  // where the depth came from (may be empty)
};

// A frame's name in outputs and logs: its depth timestamp as the input lists it, else its index.
inline std::string KeyframeName(const RgbdFrame& frame) {
  return frame.timestamp_text.empty() ? std::to_string(frame.index) : frame.timestamp_text;
}

}  // namespace gf
