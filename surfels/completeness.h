// How complete and how accurate a map is against a ground-truth mesh (the synthetic scenes'
// scene.ply), overall and per material.
//
// The mesh is sampled evenly (sample_spacing_m apart). Completeness counts only the surfaces the
// capture observed: a sample is observed when some view's true depth image (its first surface)
// sees it within observed_tolerance at its pixel, within the depth range that is fused.
// Completeness within d: the share of observed samples with a map point within d. Accuracy: each
// map point's distance to the plane of the triangle of its nearest mesh sample (at most its
// distance to that sample), median and 90th percentile, over all map points and per source (sensor,
// fills). Nearest neighbours by PCL's k-d tree (FLANN).
//
// No threads, no I/O (ReadTriangleMeshPly aside). Usage:
//   gf::TriangleMesh mesh = gf::ReadTriangleMeshPly("scene/scene.ply");
//   gf::MapScore s = gf::ScoreMap(map_in_mesh_frame, mesh, views, {});
#pragma once

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/se3.h"
#include "surfels/surfel_map.h"

namespace gf {

struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;  // metres
  std::vector<uint8_t> material;          // per vertex (0 when the file has none)
  std::vector<std::array<int, 3>> faces;
};

// A binary little-endian or ASCII PLY with vertex x y z (float) and optional `material` (uchar),
// and faces as `property list uchar int vertex_indices` (triangles; polygons are fanned). Throws
// InputError naming the file on anything else.
TriangleMesh ReadTriangleMeshPly(const std::string& path);

// A view of the ground truth: the first surface's depth (CV_32F metres, 0 = none) seen by
// `camera` at world_from_camera (the mesh's frame).
struct TruthView {
  cv::Mat depth;
  SE3 world_from_camera;
};

struct CompletenessOptions {
  double sample_spacing_m = 0.005;   // mesh samples this far apart, metres
  double observed_tolerance = 0.01;  // relative depth agreement for a sample to be observed
  double min_depth_m = 0.3, max_depth_m = 4.0;  // ... within the range that is fused, metres
  std::vector<double> within_m = {0.01, 0.02};  // completeness thresholds, metres
  bool Check(std::string* message = nullptr) const;
};

struct Completeness {
  long observed = 0;           // observed mesh samples
  std::vector<double> within;  // share within each CompletenessOptions::within_m
};

struct MapScore {
  Completeness overall;
  std::array<Completeness, 256> per_material;  // by the mesh's material label
  long map_points = 0;
  double accuracy_median_m = 0, accuracy_p90_m = 0;
  // By DepthSource (0 when none).
  std::array<double, kDepthSources> source_median_m{}, source_p90_m{};
  std::array<long, kDepthSources> source_points{};
  std::string BriefReport() const;
};

// `map`: surfels in the mesh's frame; `views` decide which samples were observed (none: all).
MapScore ScoreMap(const std::vector<Surfel>& map, const TriangleMesh& mesh, const Camera& camera,
                  const std::vector<TruthView>& views, const CompletenessOptions& options);

}  // namespace gf
