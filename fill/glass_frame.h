// Clear glass in one RGB-D frame, without learning: where the glass stands on its support and
// the depth of its surface (glassfusion fill-frame; issue 54, part 4).
//
// A depth camera reads clear glass as a hole, or reads the surface behind it (the table, the
// wall), rarely the glass itself. From one frame:
//  1. the support planes (RANSAC over the frame's depth, largest first: a floor, a table, a
//     wall), and for each object the plane read around its base;
//  2. where the glass is: holes over the supports that are not a stereo or projector shadow (a
//     shadow's run along its row lies between two depths far apart: the near edge and the far
//     background; a hole in glass lies between readings of one surface), closed over small gaps,
//     kept when large enough to be an object, each region's convex hull; or the caller's mask;
//  3. each region as an object standing on the plane, a surface of revolution (Phillips et al.,
//     RSS 2016): its axis along the plane's normal through the base, its radius per height from
//     the silhouette (a silhouette ray grazes the surface: its distance from the axis is the
//     radius there), the base where the region's lowest ray meets the plane;
//  4. the depth of that surface put in wherever the sensor read nothing or read more than
//     behind_margin_m behind it (a see-through reading), inside the region.
//
// Measured on real D435 frames (docs/experiments/2026-12-07-fill-frame.md): the shape step
// helps when the region is right; finding the region from one frame is the weak step.
//
// No threads, no I/O. Usage:
//   gf::GlassFrameResult r = gf::FindGlassInFrame(color, depth_m, camera, options);
//   cv::imwrite("glass_mask.png", r.glass_mask);  // r.depth_filled: CV_32F metres
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "acquisition/camera.h"

namespace gf {

struct GlassFrameOptions {
  // A point of the support plane lies within this of it (metres, along its normal): the
  // sensor's noise at a metre or two, with room for a cloth or a mat.
  double plane_inlier_m = 0.01;
  int plane_iterations = 400;  // RANSAC draws of three points (a fixed seed: the same result)
  // Planes glass may stand on or in (a table, a shelf, a wall), largest first; each must hold a
  // twentieth of the frame's points.
  int support_planes = 3;
  int plane_sample_step_px = 6;  // every n-th pixel each way is a RANSAC point
  // A hole run along a row whose two ends differ in depth by more than this share of the nearer
  // is a shadow (the foreground edge on one side, the background on the other), not glass.
  double shadow_relative_jump = 0.03;
  double close_m = 0.005;  // glass evidence is closed over gaps this wide (at the plane's depth)
  // A glass region covers at least this area (square metres at the plane's depth): 2 x 2 cm.
  double min_region_m2 = 4e-4;
  double height_step_m = 0.01;  // the radius is measured per step of this height (metres)
  double min_radius_m = 0.01;   // a standing glass object is this thick at least (radius, m)
  double max_radius_m = 0.25;   // ... and at most this
  double min_height_m = 0.03;   // ... and this tall at least (metres)
  // A reading more than this behind the fitted glass surface sees through it (metres).
  double behind_margin_m = 0.01;
  bool Check(std::string* message = nullptr) const;
};

// One region: a glass object found (or given) in the frame.
struct GlassFrameRegion {
  int pixels = 0;       // in the glass mask
  bool shaped = false;  // a standing surface of revolution was fitted
  float radius_m = 0;   // at its base
  float height_m = 0;   // its highest point given a depth, above the plane (metres)
  int replaced = 0;     // pixels whose depth it gave
};

struct GlassFrameResult {
  bool plane_found = false;
  // The support plane in the camera frame: normal . p + offset = 0, the normal towards the camera
  // (offset > 0).
  Eigen::Vector3d plane_normal = Eigen::Vector3d::Zero();
  double plane_offset_m = 0;
  int plane_inliers = 0;  // of the RANSAC points
  cv::Mat glass_mask;     // CV_8U, 255 where glass was found (or given)
  cv::Mat depth_filled;   // CV_32F metres: the sensor's depth, glass surface put in
  std::vector<GlassFrameRegion> regions;
  int replaced_pixels = 0;
  std::string BriefReport() const;
};

// The glass inside boxes a person drew round each glass object (image pixels): OpenCV's GrabCut
// (Rother et al. 2004) on each box and a quarter of its size round it, started from the box
// (iterations rounds). CV_32S: k + 1 where box k keeps a pixel (one object per box; where boxes
// overlap, the later box's), 0 elsewhere. The same boxes give the same regions (GrabCut's random
// start is seeded). A box outside the image is clipped; one with nothing left is skipped.
cv::Mat GlassRegionsFromBoxes(const cv::Mat& color, const std::vector<cv::Rect>& boxes,
                              int iterations = 5);

// color: CV_8UC3 (may be empty; unused today); depth_m: CV_32F metres, 0 = no reading, at the
// camera's size. given: the glass, to skip step 2: CV_8U (non-zero = glass, each connected piece
// one object) or CV_32S (label > 0 = glass, one object per label, labels 1..N with N the number
// of objects, as GlassRegionsFromBoxes gives), at the same size; or empty.
GlassFrameResult FindGlassInFrame(const cv::Mat& color, const cv::Mat& depth_m,
                                  const Camera& camera, const GlassFrameOptions& options,
                                  const cv::Mat& given = cv::Mat());

}  // namespace gf
