// Building blocks of the procedural scenes (internal to datasets/): surfaces, primitives, the
// room, and the scenes kept in datasets/scenes_glass.cc.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "datasets/scene.h"

namespace gf::synth::internal {

Surface MakeSurface(Material m, Eigen::Vector3f bgr, float contrast, float cell, uint32_t seed);
Primitive Box(const std::string& name, Eigen::Vector3d lo, Eigen::Vector3d hi, Surface s);
// A vertical cylinder standing on `base` (its bottom centre).
Primitive Cylinder(const std::string& name, Eigen::Vector3d base, double radius, double height,
                   Surface s);
Primitive Sphere(const std::string& name, Eigen::Vector3d center, double radius, Surface s);
// The room (6 x 5 x 2.8 m, inside-out box around the origin) and its floor.
void AddRoom(std::vector<Primitive>* prims, uint32_t seed);

// Where a scene's handheld trajectory looks from (Scene's focus, orbit_radius, eye_height,
// orbit_center_angle).
struct SceneView {
  Eigen::Vector3d focus{0, 0, 0.8};
  double orbit_radius = 1.6;
  double eye_height = 1.45;
  double orbit_center_angle = -1.5707963267948966;
};

// Appends the primitives of "window" or "bottles" (after the room) and returns their view.
// `wood`: the table and frame surface shared with the other scenes.
SceneView AddGlassScene(const std::string& name, uint32_t seed, const Surface& wood,
                        std::vector<Primitive>* prims);

}  // namespace gf::synth::internal
