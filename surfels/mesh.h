// A triangle mesh of the surfel map (reconstruct --mesh): PCL's greedy projection triangulation
// over the stable surfels' positions and normals (Marton et al. 2009), written as mesh.ply (binary
// PLY: vertices with normals and colour, faces), atomically.
//
// Greedy projection joins neighbouring surfels and leaves holes where the map has none: the mesh
// claims no surface the capture did not measure or fill, which matters when maps with and without
// the fill are compared. (Poisson reconstruction closes holes with surface it invents.)
//
// No threads. Usage:
//   gf::MeshSummary s = gf::WriteMapMesh(surfels, "run/mesh.ply", {});
#pragma once

#include <string>
#include <vector>

#include "surfels/surfel_map.h"

namespace gf {

struct MeshOptions {
  double search_radius_m = 0.025;  // largest edge, metres
  double neighbour_factor = 2.5;   // edges up to this many times the local point spacing
  int max_neighbours = 50;         // neighbours considered per point
  bool Check(std::string* message = nullptr) const;
};

struct MeshSummary {
  long vertices = 0;
  long faces = 0;
  double seconds = 0;
  std::string BriefReport() const;
};

MeshSummary WriteMapMesh(const std::vector<Surfel>& surfels, const std::string& path,
                         const MeshOptions& options);

}  // namespace gf
