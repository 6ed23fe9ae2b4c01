// map.ply: the surfel map as a binary little-endian PLY point cloud that PCL, Open3D, MeshLab and
// CloudCompare read. One vertex per surfel with the properties (DESIGN.md)
//   float x y z        position, world frame (the run's trajectory.txt frame), metres
//   float nx ny nz     unit normal, world frame
//   uchar red green blue
//   float radius       disc radius, metres
//   float confidence   accumulated measurement weight (fusion.h)
//   uchar source       DepthSource: 1 sensor, 2 stereo fill, 3 COLMAP, 4 carried fill,
//                      5 transparent (clear glass)
// Written atomically (a temporary name, then renamed).
#pragma once

#include <string>
#include <vector>

#include "surfels/surfel_map.h"

namespace gf {

void WriteSurfelPly(const std::string& path, const std::vector<Surfel>& surfels);
// The bytes WriteSurfelPly writes; without the normals (nx ny nz) when `normals` is false (a view
// that draws each surfel as a disc facing the viewer needs none).
std::string SurfelPlyBytes(const std::vector<Surfel>& surfels, bool normals = true);

// Reads a map.ply written by WriteSurfelPly, or any binary little-endian or ASCII PLY whose first
// element is `vertex` with float x y z (other properties are read when present, by name). Throws
// InputError naming the file on anything else.
std::vector<Surfel> ReadSurfelPly(const std::string& path);

}  // namespace gf
