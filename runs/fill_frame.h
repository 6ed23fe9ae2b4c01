// `glassfusion fill-frame`: clear glass in one RGB-D frame (fill/glass_frame.h) from files, into
// OUT/depth_filled.png, OUT/glass_mask.png, OUT/glass_overlay.png and OUT/fill_frame.json.
//
// Depth files: a 16-bit PNG (or PGM) in the camera's depth_scale units, an OpenEXR image of float
// metres (its first channel), or an OpenCV FileStorage file (.xml, .yml, .json, optionally .gz)
// of float metres (the node `depth_image` or its first node). 0, NaN and infinities are holes.
//
// Usage:
//   gf::FillFrameOptions o;  o.color_file = "rgb.jpg";  o.depth_file = "depth.exr";
//   o.camera_file = "camera.json";  o.out_dir = "out";
//   std::cout << gf::RunFillFrame(o).BriefReport();
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "fill/glass_frame.h"

namespace gf {

struct FillFrameOptions {
  std::string color_file;   // colour image (any format OpenCV reads)
  std::string depth_file;   // depth, as above
  std::string camera_file;  // camera.json (acquisition/camera.h)
  std::string out_dir;      // created if missing; only the four files named above are written
  std::string mask_file;    // optional: the glass's pixels (non-zero), to skip finding them
  // Optional, instead of mask_file: a box round each glass object (colour pixels); the glass in
  // each is cut out by colour (GlassRegionsFromBoxes), one object per box.
  std::vector<cv::Rect> boxes;
  GlassFrameOptions glass;
};

struct FillFrameSummary {
  GlassFrameResult result;
  int depth_pixels = 0;  // pixels with a sensor reading
  std::string BriefReport() const;
};

// Metric depth (CV_32F, 0 = hole) from a depth file as above; depth_scale: PNG/PGM units per
// metre. Throws InputError naming the file when it cannot be read or holds no depth image.
cv::Mat ReadMetricDepth(const std::string& path, double depth_scale);

// A box "x,y,w,h" (pixels, w and h > 0); throws InputError naming `what` when it is not one.
cv::Rect ParseBox(const std::string& text, const std::string& what);

// Reads, finds the glass, writes. Throws InputError (one line naming the file) on bad input.
FillFrameSummary RunFillFrame(const FillFrameOptions& options);

}  // namespace gf
