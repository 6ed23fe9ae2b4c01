// The clear-glass scenes: "window" (a wall with a glazed opening, things seen through it) and
// "bottles" (clear bottles and glasses of several shapes among diffuse things on a table).
#include <Eigen/Core>
#include <stdexcept>

#include "datasets/scene_parts.h"

namespace gf::synth::internal {
namespace {

Surface Glass(uint32_t seed) {
  return MakeSurface(Material::kClearGlass, {0.82f, 0.90f, 0.86f}, 0.0f, 0.01f, seed);
}

Surface Matte(Eigen::Vector3f bgr, float cell, uint32_t seed) {
  return MakeSurface(Material::kDiffuse, bgr, 0.5f, cell, seed);
}

// A partition wall across the room at y 0.40-0.50 with an opening x -0.55..0.55, z 0.75..1.85;
// a wooden frame 6 cm wide standing 3 cm proud of the wall; a 1 cm clear pane in the middle of
// the wall's thickness; furniture behind the wall and a cabinet in front.
SceneView AddWindow(uint32_t seed, const Surface& wood, std::vector<Primitive>* p) {
  const Surface plaster =
      MakeSurface(Material::kDiffuse, {0.70f, 0.74f, 0.76f}, 0.4f, 0.01f, seed + 40);
  const double y0 = 0.40, y1 = 0.50, x = 0.55, z0 = 0.75, z1 = 1.85, f = 0.06;
  p->push_back(Box("wall left", {-3.0, y0, 0.0}, {-x, y1, 2.8}, plaster));
  p->push_back(Box("wall right", {x, y0, 0.0}, {3.0, y1, 2.8}, plaster));
  p->push_back(Box("wall below", {-x, y0, 0.0}, {x, y1, z0}, plaster));
  p->push_back(Box("wall above", {-x, y0, z1}, {x, y1, 2.8}, plaster));
  const double front = y0 - 0.03;
  p->push_back(Box("frame left", {-x, front, z0}, {-x + f, y1, z1}, wood));
  p->push_back(Box("frame right", {x - f, front, z0}, {x, y1, z1}, wood));
  p->push_back(Box("frame sill", {-x + f, front, z0}, {x - f, y1, z0 + f}, wood));
  p->push_back(Box("frame head", {-x + f, front, z1 - f}, {x - f, y1, z1}, wood));
  p->push_back(Box("pane", {-x + f, 0.445, z0 + f}, {x - f, 0.455, z1 - f}, Glass(seed + 41)));
  // Behind the window.
  p->push_back(Box("bookcase", {-0.45, 1.2, 0.0}, {-0.1, 1.5, 1.3},
                   Matte({0.30f, 0.45f, 0.70f}, 0.006f, seed + 42)));
  p->push_back(Box("pedestal", {0.1, 0.9, 0.0}, {0.45, 1.2, 0.95},
                   Matte({0.55f, 0.50f, 0.35f}, 0.008f, seed + 43)));
  p->push_back(
      Sphere("globe", {0.27, 1.05, 1.07}, 0.12, Matte({0.25f, 0.60f, 0.40f}, 0.005f, seed + 44)));
  p->push_back(Cylinder("lamp", {-0.05, 0.85, 0.0}, 0.05, 1.6,
                        Matte({0.60f, 0.35f, 0.30f}, 0.004f, seed + 45)));
  // In front of the wall.
  p->push_back(Box("cabinet", {0.7, 0.0, 0.0}, {1.1, 0.37, 0.8},
                   Matte({0.35f, 0.55f, 0.45f}, 0.008f, seed + 46)));
  SceneView view;
  view.focus = {0.0, 0.45, 1.3};
  view.orbit_radius = 1.8;
  view.eye_height = 1.4;
  return view;
}

// A table as in "glass-table" holding clear glasses (cylinders of several radii and heights),
// two bottles (a body and a narrower neck), a bowl (a sphere sunk into the top) and a vase,
// beside a book, a mug and a box that the tracker can hold on to.
SceneView AddBottles(uint32_t seed, const Surface& wood, std::vector<Primitive>* p) {
  p->push_back(Box("table top", {-0.6, -0.4, 0.72}, {0.6, 0.4, 0.76}, wood));
  for (double x : {-0.56, 0.52})
    for (double y : {-0.36, 0.32})
      p->push_back(Box("table leg", {x, y, 0.0}, {x + 0.04, y + 0.04, 0.72}, wood));
  const double top = 0.76;
  p->push_back(Cylinder("tall glass", {-0.32, 0.12, top}, 0.035, 0.15, Glass(seed + 50)));
  p->push_back(Cylinder("tumbler", {-0.12, -0.12, top}, 0.045, 0.09, Glass(seed + 51)));
  p->push_back(Cylinder("bottle", {0.05, 0.15, top}, 0.04, 0.20, Glass(seed + 52)));
  p->push_back(Cylinder("bottle neck", {0.05, 0.15, top + 0.20}, 0.014, 0.09, Glass(seed + 52)));
  p->push_back(Cylinder("wine bottle", {0.28, 0.02, top}, 0.036, 0.17, Glass(seed + 53)));
  p->push_back(
      Cylinder("wine bottle neck", {0.28, 0.02, top + 0.17}, 0.012, 0.11, Glass(seed + 53)));
  p->push_back(Sphere("bowl", {-0.35, -0.18, top + 0.04}, 0.07, Glass(seed + 54)));
  p->push_back(Cylinder("vase", {0.42, 0.25, top}, 0.05, 0.24, Glass(seed + 55)));
  p->push_back(Box("book", {0.15, -0.30, top}, {0.36, -0.16, top + 0.04},
                   Matte({0.25f, 0.30f, 0.70f}, 0.004f, seed + 56)));
  p->push_back(Cylinder("mug", {0.45, -0.2, top}, 0.04, 0.10,
                        Matte({0.30f, 0.55f, 0.85f}, 0.003f, seed + 57)));
  p->push_back(Box("box", {-0.55, 0.2, top}, {-0.42, 0.34, top + 0.16},
                   Matte({0.55f, 0.45f, 0.30f}, 0.004f, seed + 58)));
  p->push_back(Box("crate", {0.9, 0.6, 0.0}, {1.3, 1.0, 0.45},
                   Matte({0.35f, 0.55f, 0.45f}, 0.008f, seed + 59)));
  SceneView view;
  view.focus = {0.0, 0.0, 0.85};
  view.orbit_radius = 1.3;
  view.eye_height = 1.35;
  return view;
}

}  // namespace

SceneView AddGlassScene(const std::string& name, uint32_t seed, const Surface& wood,
                        std::vector<Primitive>* prims) {
  if (name == "window") return AddWindow(seed, wood, prims);
  if (name == "bottles") return AddBottles(seed, wood, prims);
  throw std::invalid_argument("not a glass scene: \"" + name + "\"");
}

}  // namespace gf::synth::internal
