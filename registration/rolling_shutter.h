// The depth sensor's rolling shutter: a model of when each row of a depth image was exposed, and
// the image as the camera would have seen it at one instant.
//
// A rolling-shutter sensor exposes its rows one after another over its readout time. The Kinect
// v1 computes depth from such an infrared sensor, read out over the frame period (1/30 s at 30
// frames/s): when the camera moves, the top of the scene is seen from one place and the bottom
// from another, and an alignment of the whole image mixes the two. A frame is stamped when its
// last row has been read out (as USB video drivers stamp a frame at its end), so the stamp's
// instant is the last row's: row y of an image of H rows was exposed
//   dt(y) = ((y + 0.5) / H - 1) * readout_s   seconds relative to the stamp (<= 0)
// (for a top-to-bottom readout; the others count their lines the same way).
// The rows are read from the image's top to its bottom unless the sensor says otherwise: a
// capture whose images were turned in software (a quarter turn: tests/rotate_capture.py) reads
// its sensor rows along the turned image's columns.
//
// A camera moving with the twist [v; w] (its own frame: metres and radians per second) saw the
// point p of row y from where it was dt(y) earlier; at the stamp's instant the point lies at
//   p' = p + (w x p + v) dt(y)      (first order in the motion during the readout).
//
// No threads, no I/O.
#pragma once

#include <opencv2/core.hpp>

#include "acquisition/camera.h"
#include "acquisition/se3.h"

namespace gf {

// The depth image as seen at the last row's instant by a camera moving with `twist_per_s`, on
// the camera's own pixels (with its lens distortion): every measured point moved by the formula
// above and drawn at its new pixel, the nearest point winning; a measured pixel that no moved
// point lands on keeps its own point's new depth (the motion within one readout moves points by
// about a pixel, which would otherwise leave cracks). Rows are the sensor's: the image as the
// camera gave it, before undistortion. Immutable after construction.
class RollingShutter {
 public:
  RollingShutter(const Camera& camera, double readout_s,
                 ReadoutOrder order = ReadoutOrder::kTopToBottom);
  // depth: CV_32F metres (0 = none) of the camera's size.
  cv::Mat DepthAtLastRow(const cv::Mat& depth, const SE3::Tangent& twist_per_s) const;
  double readout_s() const { return readout_s_; }

 private:
  Camera camera_;
  UndistortedPixels rays_;
  double readout_s_;
  ReadoutOrder order_;
};

}  // namespace gf
