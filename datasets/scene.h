// Procedural indoor scenes with glass and shiny objects, and a CPU ray caster for them.
//
// A scene is a handful of primitives (boxes, the room as an inside-out box, vertical cylinders,
// spheres), each with a material and a procedural solid texture (multi-octave value noise on the
// world position, so a surface point looks the same from every viewpoint and stereo can match it).
// World frame: metres, z up; the table stands around the origin.
//
// Materials say what the colour camera and the Kinect see:
//   kDiffuse       the Kinect measures it;
//   kGlossy        shiny textured metal: colour sees texture plus highlights, the Kinect no return;
//   kDark          matte black absorbing: low-contrast texture, no return;
//   kTexturedGlass frosted / printed glass: colour sees its texture, no return;
//   kClearGlass    clear glass: colour sees the background through it (slightly tinted); the Kinect
//                  reads the surface behind it, the glass itself, or nothing (synth.h).
// Deterministic: the same name and seed give the same scene on every machine.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace gf::synth {

enum class Material : uint8_t {
  kDiffuse = 0,
  kGlossy = 1,
  kDark = 2,
  kTexturedGlass = 3,
  kClearGlass = 4,
};
constexpr uint8_t kNoSurface = 255;  // label of a pixel whose ray leaves the scene
inline bool FailsInfrared(Material m) { return m != Material::kDiffuse; }
const char* MaterialName(Material m);

struct Surface {
  Material material = Material::kDiffuse;
  Eigen::Vector3f base_bgr{0.6f, 0.6f, 0.6f};  // mean colour, BGR in [0, 1]
  float texture_contrast = 0.35f;              // relative amplitude of the texture, 0 = flat
  float texture_cell_m = 0.02f;                // finest texture cell, metres
  uint32_t texture_seed = 1;
};

struct Primitive {
  enum class Kind { kBox, kRoom, kCylinder, kSphere };
  Kind kind = Kind::kBox;
  Eigen::Vector3d min_corner{0, 0, 0};  // box / room
  Eigen::Vector3d max_corner{0, 0, 0};
  Eigen::Vector3d center{0, 0, 0};  // sphere centre; cylinder base centre (axis along +z)
  double radius = 0;                // sphere / cylinder, metres
  double height = 0;                // cylinder, metres
  Surface surface;
  std::string name;
};

struct Hit {
  double t = 0;                                       // distance along the (unit) ray, metres
  Eigen::Vector3d point = Eigen::Vector3d::Zero();    // in world
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit, facing the ray origin
  int primitive = -1;
};

class Scene {
 public:
  // Names: "glass-table", "shelf", "window" (a wall with a clear glass panel in a frame, things
  // behind it), "bottles" (clear bottles and glasses on a table). Throws std::invalid_argument
  // for an unknown name.
  static Scene Make(const std::string& name, uint32_t seed);
  static std::vector<std::string> Names();

  // Nearest hit with t in (t_min, t_max); skip_clear_glass ignores clear-glass primitives (what
  // the colour camera sees through them). False when the ray leaves the scene.
  bool Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_min,
                 double t_max, bool skip_clear_glass, Hit* hit) const;
  // Colour (BGR, 0..1) of a hit seen from `view_direction` (unit, towards the surface).
  Eigen::Vector3f Shade(const Hit& hit, const Eigen::Vector3d& view_direction) const;

  const std::vector<Primitive>& primitives() const { return primitives_; }
  const std::string& name() const { return name_; }
  // Where the handheld trajectory looks, and how far from it the camera moves (metres).
  Eigen::Vector3d focus() const { return focus_; }
  double orbit_radius() const { return orbit_radius_; }
  double eye_height() const { return eye_height_; }
  // Direction (radians, about +z from +x) of the orbit's middle, seen from the focus.
  double orbit_center_angle() const { return orbit_center_angle_; }

  // Triangle mesh of every surface as binary little-endian PLY: vertices (x y z float, material
  // uchar) and faces (vertex_indices), the ground truth for map accuracy and completeness.
  void WritePly(const std::string& path) const;

 private:
  std::string name_;
  std::vector<Primitive> primitives_;
  Eigen::Vector3d light_{0, 0, 2.8};
  Eigen::Vector3d focus_{0, 0, 0.8};
  double orbit_radius_ = 1.6;
  double eye_height_ = 1.45;
  double orbit_center_angle_ = -1.5707963267948966;
};

// Solid value noise in [0, 1], smooth, deterministic for (point, seed).
float ValueNoise(const Eigen::Vector3d& point, uint32_t seed);
// Deterministic uniform number in [0, 1] for integer coordinates and a seed (sensor noise that
// does not depend on the order pixels are rendered in).
float HashUniform(int32_t x, int32_t y, int32_t z, uint32_t seed);

}  // namespace gf::synth
