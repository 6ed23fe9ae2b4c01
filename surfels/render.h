// Rendering surfels as discs into a camera (a CPU splat renderer): colour and depth images of a
// map from any viewpoint, for reports and for frame-to-model tracking (the model's depth at the
// predicted pose).
//
// Each surfel covers the pixels within its radius (r f / z pixels) around its projection, nearest
// depth first; colour is the surfel's own (a transparent surfel's, the colour seen through it,
// blended with glass_tint), optionally shaded by how squarely its normal faces the camera (so that
// shapes read in a picture).
//
// No threads, no I/O. Usage:
//   gf::SurfelImage image = gf::RenderSurfels(surfels, camera, world_from_camera, {});
//   cv::imwrite("view.png", image.color);
#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/se3.h"
#include "surfels/surfel_map.h"

namespace gf {

struct RenderOptions {
  bool shade = true;                    // colour times (0.35 + 0.65 |n . view|)
  int max_splat_px = 8;                 // largest disc radius drawn, pixels
  double min_depth_m = 0.1;             // nearer surfels are not drawn
  cv::Vec3b background{255, 255, 255};  // BGR where nothing is drawn
  // Transparent surfels (DepthSource::kTransparent, clear glass) are drawn half their own colour,
  // half this BGR colour (cyan), so that the glass shows as glass.
  cv::Vec3b glass_tint{255, 200, 0};
  bool Check(std::string* message = nullptr) const;
};

struct SurfelImage {
  cv::Mat color;  // CV_8UC3 BGR
  cv::Mat depth;  // CV_32F metres along the optical axis, 0 = none
};

// The camera's projection includes its lens distortion (as the frames' pixels do).
SurfelImage RenderSurfels(const std::vector<Surfel>& surfels, const Camera& camera,
                          const SE3& world_from_camera, const RenderOptions& options);

// Closes the gaps that discs leave between the surfels of one surface in a rendered depth image
// (neighbouring discs seen from another viewpoint than the one they were measured from do not
// tile the image). A pixel where `fillable` (CV_8U, non-zero; empty = every pixel) and depth is 0
// takes the depth interpolated between the two drawn pixels that enclose it along a row, a column
// or a diagonal, when they are at most max_gap_px + 1 apart (so at most max_gap_px empty pixels
// lie between them) and their depths differ by at most max_relative_step of the nearer: one
// surface, not an edge. The shortest such span decides. Nothing extends past a drawn region's
// border: a pixel must be enclosed on both sides. Pixels filled here do not enclose others.
// Returns the count filled.
int CloseSplatGaps(cv::Mat* depth, const cv::Mat& fillable, int max_gap_px,
                   double max_relative_step);

// A viewpoint that sees the whole map: looking at its centroid from `direction` (world frame, from
// the camera towards the map), far enough that the map's extent fills about 80% of the image.
SE3 ViewOfMap(const std::vector<Surfel>& surfels, const Camera& camera,
              const Eigen::Vector3d& direction, const Eigen::Vector3d& up);

}  // namespace gf
