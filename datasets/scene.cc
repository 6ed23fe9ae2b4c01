#include "datasets/scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "datasets/scene_parts.h"

namespace gf::synth {
namespace {

uint32_t Hash(int32_t x, int32_t y, int32_t z, uint32_t seed) {
  uint32_t h = seed * 0x9E3779B1u;
  h ^= static_cast<uint32_t>(x) * 0x85EBCA77u;
  h = (h << 13) | (h >> 19);
  h ^= static_cast<uint32_t>(y) * 0xC2B2AE3Du;
  h = (h << 13) | (h >> 19);
  h ^= static_cast<uint32_t>(z) * 0x27D4EB2Fu;
  h ^= h >> 15;
  h *= 0x2C1B3C6Du;
  h ^= h >> 12;
  h *= 0x297A2D39u;
  h ^= h >> 15;
  return h;
}

float Lattice(int32_t x, int32_t y, int32_t z, uint32_t seed) {
  return (Hash(x, y, z, seed) & 0xFFFFFF) / static_cast<float>(0xFFFFFF);
}

float Smooth(float t) { return t * t * (3.f - 2.f * t); }

// Slab test; returns entry and exit distances and the entry/exit axes.
bool SlabInterval(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo,
                  const Eigen::Vector3d& hi, double* t_in, double* t_out, int* axis_in,
                  int* axis_out) {
  *t_in = -std::numeric_limits<double>::infinity();
  *t_out = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-15) {
      if (o[a] < lo[a] || o[a] > hi[a]) return false;
      continue;
    }
    double t0 = (lo[a] - o[a]) / d[a], t1 = (hi[a] - o[a]) / d[a];
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > *t_in) {
      *t_in = t0;
      *axis_in = a;
    }
    if (t1 < *t_out) {
      *t_out = t1;
      *axis_out = a;
    }
  }
  return *t_in <= *t_out;
}

bool IntersectPrimitive(const Primitive& p, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                        double t_min, double t_max, double* t, Eigen::Vector3d* normal) {
  switch (p.kind) {
    case Primitive::Kind::kBox:
    case Primitive::Kind::kRoom: {
      double t_in, t_out;
      int a_in = 0, a_out = 0;
      if (!SlabInterval(o, d, p.min_corner, p.max_corner, &t_in, &t_out, &a_in, &a_out))
        return false;
      const bool room = p.kind == Primitive::Kind::kRoom;
      const double tt = room ? t_out : t_in;
      const int axis = room ? a_out : a_in;
      if (!(tt > t_min && tt < t_max)) return false;
      *t = tt;
      *normal = Eigen::Vector3d::Zero();
      (*normal)[axis] = d[axis] > 0 ? -1.0 : 1.0;
      return true;
    }
    case Primitive::Kind::kSphere: {
      const Eigen::Vector3d oc = o - p.center;
      const double b = oc.dot(d), c = oc.squaredNorm() - p.radius * p.radius;
      const double disc = b * b - c;
      if (disc < 0) return false;
      const double s = std::sqrt(disc);
      for (double tt : {-b - s, -b + s}) {
        if (tt > t_min && tt < t_max) {
          *t = tt;
          *normal = (o + tt * d - p.center).normalized();
          if (normal->dot(d) > 0) *normal = -*normal;
          return true;
        }
      }
      return false;
    }
    case Primitive::Kind::kCylinder: {
      double best = t_max;
      bool found = false;
      // Side: (x - cx)^2 + (y - cy)^2 = r^2 with z in [base, base + h].
      const double ox = o.x() - p.center.x(), oy = o.y() - p.center.y();
      const double a = d.x() * d.x() + d.y() * d.y();
      if (a > 1e-15) {
        const double b = ox * d.x() + oy * d.y(), c = ox * ox + oy * oy - p.radius * p.radius;
        const double disc = b * b - a * c;
        if (disc >= 0) {
          const double s = std::sqrt(disc);
          for (double tt : {(-b - s) / a, (-b + s) / a}) {
            const double z = o.z() + tt * d.z();
            if (tt > t_min && tt < best && z >= p.center.z() && z <= p.center.z() + p.height) {
              best = tt;
              found = true;
              *normal = Eigen::Vector3d(ox + tt * d.x(), oy + tt * d.y(), 0).normalized();
              break;
            }
          }
        }
      }
      // Caps.
      if (std::abs(d.z()) > 1e-15) {
        for (double zc : {p.center.z(), p.center.z() + p.height}) {
          const double tt = (zc - o.z()) / d.z();
          if (!(tt > t_min && tt < best)) continue;
          const double x = ox + tt * d.x(), y = oy + tt * d.y();
          if (x * x + y * y > p.radius * p.radius) continue;
          best = tt;
          found = true;
          *normal = Eigen::Vector3d(0, 0, 1);
        }
      }
      if (!found) return false;
      *t = best;
      if (normal->dot(d) > 0) *normal = -*normal;
      return true;
    }
  }
  return false;
}

}  // namespace

namespace internal {

Surface MakeSurface(Material m, Eigen::Vector3f bgr, float contrast, float cell, uint32_t seed) {
  Surface s;
  s.material = m;
  s.base_bgr = bgr;
  s.texture_contrast = contrast;
  s.texture_cell_m = cell;
  s.texture_seed = seed;
  return s;
}

Primitive Box(const std::string& name, Eigen::Vector3d lo, Eigen::Vector3d hi, Surface s) {
  Primitive p;
  p.kind = Primitive::Kind::kBox;
  p.name = name;
  p.min_corner = lo;
  p.max_corner = hi;
  p.surface = s;
  return p;
}

Primitive Cylinder(const std::string& name, Eigen::Vector3d base, double radius, double height,
                   Surface s) {
  Primitive p;
  p.kind = Primitive::Kind::kCylinder;
  p.name = name;
  p.center = base;
  p.radius = radius;
  p.height = height;
  p.surface = s;
  return p;
}

Primitive Sphere(const std::string& name, Eigen::Vector3d center, double radius, Surface s) {
  Primitive p;
  p.kind = Primitive::Kind::kSphere;
  p.name = name;
  p.center = center;
  p.radius = radius;
  p.surface = s;
  return p;
}

void AddRoom(std::vector<Primitive>* prims, uint32_t seed) {
  Primitive room;
  room.kind = Primitive::Kind::kRoom;
  room.name = "room";
  room.min_corner = {-3.0, -2.5, 0.0};
  room.max_corner = {3.0, 2.5, 2.8};
  room.surface = MakeSurface(Material::kDiffuse, {0.62f, 0.72f, 0.80f}, 0.45f, 0.012f, seed + 1);
  prims->push_back(room);
  prims->push_back(
      Box("floor", {-3.0, -2.5, -0.02}, {3.0, 2.5, 0.0},
          MakeSurface(Material::kDiffuse, {0.25f, 0.40f, 0.55f}, 0.5f, 0.01f, seed + 2)));
}

}  // namespace internal

using internal::AddRoom;
using internal::Box;
using internal::Cylinder;
using internal::MakeSurface;
using internal::Sphere;

const char* MaterialName(Material m) {
  switch (m) {
    case Material::kDiffuse:
      return "diffuse";
    case Material::kGlossy:
      return "glossy";
    case Material::kDark:
      return "dark";
    case Material::kTexturedGlass:
      return "textured_glass";
    case Material::kClearGlass:
      return "clear_glass";
  }
  return "unknown";
}

float HashUniform(int32_t x, int32_t y, int32_t z, uint32_t seed) { return Lattice(x, y, z, seed); }

float ValueNoise(const Eigen::Vector3d& point, uint32_t seed) {
  const double fx = std::floor(point.x()), fy = std::floor(point.y()), fz = std::floor(point.z());
  const int32_t x = static_cast<int32_t>(fx), y = static_cast<int32_t>(fy),
                z = static_cast<int32_t>(fz);
  const float tx = Smooth(static_cast<float>(point.x() - fx));
  const float ty = Smooth(static_cast<float>(point.y() - fy));
  const float tz = Smooth(static_cast<float>(point.z() - fz));
  auto lerp = [](float a, float b, float t) { return a + (b - a) * t; };
  const float c00 = lerp(Lattice(x, y, z, seed), Lattice(x + 1, y, z, seed), tx);
  const float c10 = lerp(Lattice(x, y + 1, z, seed), Lattice(x + 1, y + 1, z, seed), tx);
  const float c01 = lerp(Lattice(x, y, z + 1, seed), Lattice(x + 1, y, z + 1, seed), tx);
  const float c11 = lerp(Lattice(x, y + 1, z + 1, seed), Lattice(x + 1, y + 1, z + 1, seed), tx);
  return lerp(lerp(c00, c10, ty), lerp(c01, c11, ty), tz);
}

std::vector<std::string> Scene::Names() { return {"glass-table", "shelf", "window", "bottles"}; }

namespace {

// The glass table: a wooden table with cups, bottles (one clear), a metal ball and can, a black
// box; a crate on the floor.
internal::SceneView AddGlassTable(uint32_t seed, const Surface& wood, std::vector<Primitive>* prims) {
  std::vector<Primitive>& p = *prims;
  p.push_back(Box("table top", {-0.6, -0.4, 0.72}, {0.6, 0.4, 0.76}, wood));
  for (double x : {-0.56, 0.52})
    for (double y : {-0.36, 0.32})
      p.push_back(Box("table leg", {x, y, 0.0}, {x + 0.04, y + 0.04, 0.72}, wood));
  p.push_back(Cylinder(
      "frosted cup", {-0.30, 0.10, 0.76}, 0.04, 0.11,
      MakeSurface(Material::kTexturedGlass, {0.85f, 0.80f, 0.72f}, 0.4f, 0.004f, seed + 10)));
  p.push_back(Cylinder(
      "printed cup", {0.25, -0.15, 0.76}, 0.045, 0.10,
      MakeSurface(Material::kTexturedGlass, {0.55f, 0.75f, 0.85f}, 0.55f, 0.003f, seed + 11)));
  p.push_back(Cylinder(
      "clear bottle", {0.0, 0.15, 0.76}, 0.04, 0.25,
      MakeSurface(Material::kClearGlass, {0.80f, 0.90f, 0.85f}, 0.0f, 0.01f, seed + 12)));
  p.push_back(
      Cylinder("bottle label", {0.0, 0.15, 0.84}, 0.0405, 0.08,
               MakeSurface(Material::kDiffuse, {0.30f, 0.55f, 0.90f}, 0.6f, 0.003f, seed + 13)));
  p.push_back(Cylinder(
      "tinted bottle", {0.35, 0.20, 0.76}, 0.035, 0.22,
      MakeSurface(Material::kTexturedGlass, {0.35f, 0.65f, 0.30f}, 0.45f, 0.004f, seed + 14)));
  p.push_back(
      Sphere("metal ball", {-0.12, -0.18, 0.83}, 0.07,
             MakeSurface(Material::kGlossy, {0.70f, 0.70f, 0.72f}, 0.45f, 0.004f, seed + 15)));
  p.push_back(
      Cylinder("metal can", {0.45, -0.25, 0.76}, 0.035, 0.12,
               MakeSurface(Material::kGlossy, {0.55f, 0.60f, 0.75f}, 0.5f, 0.003f, seed + 16)));
  p.push_back(Box("black box", {-0.50, -0.30, 0.76}, {-0.38, -0.10, 0.86},
                  MakeSurface(Material::kDark, {0.07f, 0.07f, 0.08f}, 0.6f, 0.004f, seed + 17)));
  p.push_back(
      Box("crate", {0.9, 0.6, 0.0}, {1.3, 1.0, 0.45},
          MakeSurface(Material::kDiffuse, {0.35f, 0.55f, 0.45f}, 0.5f, 0.008f, seed + 18)));
  return {{0.0, 0.0, 0.82}, 1.5, 1.45, -1.5707963267948966};
}

// A shelf of three boards, each with a jar, a clear vase, a can, a black box and a book.
internal::SceneView AddShelf(uint32_t seed, const Surface& wood, std::vector<Primitive>* prims) {
  std::vector<Primitive>& p = *prims;
  p.push_back(Box("shelf back", {-0.8, 1.15, 0.0}, {0.8, 1.25, 1.8}, wood));
  for (double x : {-0.82, 0.8})
    p.push_back(Box("shelf side", {x, 0.85, 0.0}, {x + 0.02, 1.25, 1.8}, wood));
  for (double z : {0.0, 0.45, 0.9, 1.35})
    p.push_back(Box("shelf board", {-0.8, 0.85, z}, {0.8, 1.15, z + 0.02}, wood));
  uint32_t k = 20;
  // Items at different depths on each board: front (y ~ 0.92) and back (y ~ 1.08).
  for (double z : {0.02, 0.47, 0.92}) {
    p.push_back(Cylinder(
        "glass jar", {-0.55, 0.95, z}, 0.05, 0.16,
        MakeSurface(Material::kTexturedGlass, {0.80f, 0.78f, 0.70f}, 0.45f, 0.004f, seed + k++)));
    p.push_back(Cylinder(
        "clear vase", {-0.2, 1.05, z}, 0.045, 0.22,
        MakeSurface(Material::kClearGlass, {0.85f, 0.90f, 0.90f}, 0.0f, 0.01f, seed + k++)));
    p.push_back(Cylinder(
        "metal can", {0.1, 0.93, z}, 0.035, 0.12,
        MakeSurface(Material::kGlossy, {0.65f, 0.62f, 0.60f}, 0.5f, 0.003f, seed + k++)));
    p.push_back(
        Box("black box", {0.3, 1.0, z}, {0.45, 1.12, z + 0.14},
            MakeSurface(Material::kDark, {0.06f, 0.06f, 0.07f}, 0.6f, 0.004f, seed + k++)));
    p.push_back(
        Box("book", {0.55, 0.95, z}, {0.62, 1.12, z + 0.2},
            MakeSurface(Material::kDiffuse, {0.25f, 0.30f, 0.70f}, 0.5f, 0.004f, seed + k++)));
  }
  p.push_back(
      Sphere("metal ball", {0.0, 0.95, 1.43}, 0.06,
             MakeSurface(Material::kGlossy, {0.72f, 0.72f, 0.74f}, 0.45f, 0.004f, seed + k++)));
  return {{0.0, 1.0, 0.8}, 1.7, 1.2, -1.5707963267948966};
}

}  // namespace

Scene Scene::Make(const std::string& name, uint32_t seed) {
  Scene s;
  s.name_ = name;
  auto& p = s.primitives_;
  AddRoom(&p, seed);
  const Surface wood =
      MakeSurface(Material::kDiffuse, {0.20f, 0.38f, 0.58f}, 0.5f, 0.006f, seed + 3);
  internal::SceneView view;
  if (name == "glass-table") {
    view = AddGlassTable(seed, wood, &p);
  } else if (name == "shelf") {
    view = AddShelf(seed, wood, &p);
  } else if (name == "window" || name == "bottles") {
    view = internal::AddGlassScene(name, seed, wood, &p);
  } else {
    throw std::invalid_argument("unknown scene \"" + name +
                                "\" (known: glass-table, shelf, window, bottles)");
  }
  s.focus_ = view.focus;
  s.orbit_radius_ = view.orbit_radius;
  s.eye_height_ = view.eye_height;
  s.orbit_center_angle_ = view.orbit_center_angle;
  s.light_ = s.focus_ + Eigen::Vector3d(0.4, -0.6, 1.9);
  return s;
}

bool Scene::Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_min,
                      double t_max, bool skip_clear_glass, Hit* hit) const {
  bool found = false;
  double best = t_max;
  for (size_t i = 0; i < primitives_.size(); ++i) {
    const Primitive& p = primitives_[i];
    if (skip_clear_glass && p.surface.material == Material::kClearGlass) continue;
    double t;
    Eigen::Vector3d n;
    if (IntersectPrimitive(p, origin, direction, t_min, best, &t, &n)) {
      best = t;
      found = true;
      hit->t = t;
      hit->normal = n;
      hit->primitive = static_cast<int>(i);
    }
  }
  if (found) hit->point = origin + hit->t * direction;
  return found;
}

Eigen::Vector3f Scene::Shade(const Hit& hit, const Eigen::Vector3d& view_direction) const {
  const Surface& s = primitives_[hit.primitive].surface;
  Eigen::Vector3f albedo;
  for (int c = 0; c < 3; ++c) {
    // Four octaves, finest first; each channel has its own noise so the texture is colourful.
    float n = 0.f, weight_sum = 0.f, cell = s.texture_cell_m, weight = 0.3f;
    for (int octave = 0; octave < 4; ++octave) {
      n += weight * ValueNoise(hit.point / cell, s.texture_seed * 7919u + c * 131u + octave);
      weight_sum += weight;
      cell *= 3.1f;
      weight = octave == 0 ? 0.3f : 0.2f;
    }
    n /= weight_sum;
    albedo[c] = s.base_bgr[c] * (1.f + s.texture_contrast * (4.f * n - 2.f));
  }
  const Eigen::Vector3d to_light = (light_ - hit.point).normalized();
  const double lambert = std::max(0.0, hit.normal.dot(to_light));
  Eigen::Vector3f color = albedo * static_cast<float>(0.45 + 0.55 * lambert);
  if (s.material == Material::kGlossy) {
    const Eigen::Vector3d reflected =
        view_direction - 2.0 * view_direction.dot(hit.normal) * hit.normal;
    const double spec = std::pow(std::max(0.0, reflected.dot(to_light)), 40.0);
    color += Eigen::Vector3f::Constant(static_cast<float>(0.7 * spec));
  }
  return color.cwiseMax(0.f).cwiseMin(1.f);
}

namespace {

// The triangles of the scene's primitives, each vertex labelled with its material.
struct LabelledMesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<uint8_t> labels;
  std::vector<std::array<int, 3>> faces;

  void Quad(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
            const Eigen::Vector3d& d, uint8_t label) {
    const int base = static_cast<int>(vertices.size());
    for (const auto& v : {a, b, c, d}) {
      vertices.push_back(v.cast<float>());
      labels.push_back(label);
    }
    faces.push_back({base, base + 1, base + 2});
    faces.push_back({base, base + 2, base + 3});
  }
  void Tri(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
           uint8_t label) {
    const int base = static_cast<int>(vertices.size());
    for (const auto& v : {a, b, c}) {
      vertices.push_back(v.cast<float>());
      labels.push_back(label);
    }
    faces.push_back({base, base + 1, base + 2});
  }
};

void AddPrimitive(const Primitive& p, LabelledMesh* mesh) {
  const uint8_t label = static_cast<uint8_t>(p.surface.material);
  switch (p.kind) {
    case Primitive::Kind::kBox:
    case Primitive::Kind::kRoom: {
      const Eigen::Vector3d& lo = p.min_corner;
      const Eigen::Vector3d& hi = p.max_corner;
      auto corner = [&](int i) {
        return Eigen::Vector3d(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(),
                               i & 4 ? hi.z() : lo.z());
      };
      const int f[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
      for (const auto& q : f) mesh->Quad(corner(q[0]), corner(q[1]), corner(q[2]), corner(q[3]), label);
      break;
    }
    case Primitive::Kind::kCylinder: {
      const int n = 48;
      for (int i = 0; i < n; ++i) {
        const double a0 = 2 * M_PI * i / n, a1 = 2 * M_PI * (i + 1) / n;
        const Eigen::Vector3d r0(p.radius * std::cos(a0), p.radius * std::sin(a0), 0);
        const Eigen::Vector3d r1(p.radius * std::cos(a1), p.radius * std::sin(a1), 0);
        const Eigen::Vector3d up(0, 0, p.height);
        mesh->Quad(p.center + r0, p.center + r1, p.center + r1 + up, p.center + r0 + up, label);
        mesh->Tri(p.center + up, p.center + r0 + up, p.center + r1 + up, label);
        mesh->Tri(p.center, p.center + r1, p.center + r0, label);
      }
      break;
    }
    case Primitive::Kind::kSphere: {
      const int n = 24;
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < 2 * n; ++j) {
          auto at = [&](int a, int b) -> Eigen::Vector3d {
            const double th = M_PI * a / n, ph = M_PI * b / n;
            return p.center + p.radius * Eigen::Vector3d(std::sin(th) * std::cos(ph),
                                                         std::sin(th) * std::sin(ph),
                                                         std::cos(th));
          };
          mesh->Quad(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1), label);
        }
      }
      break;
    }
  }
}

}  // namespace

void Scene::WritePly(const std::string& path) const {
  LabelledMesh mesh;
  for (const Primitive& p : primitives_) AddPrimitive(p, &mesh);
  const std::vector<Eigen::Vector3f>& vertices = mesh.vertices;
  const std::vector<uint8_t>& labels = mesh.labels;
  const std::vector<std::array<int, 3>>& faces = mesh.faces;
  WriteFileAtomically(path, [&](const std::string& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    if (!out) throw InputError(path, "cannot open for writing");
    out << "ply\nformat binary_little_endian 1.0\ncomment GlassFusion synthetic scene " << name_
        << " (material: 0 diffuse, 1 glossy, 2 dark, 3 textured glass, 4 clear glass)\n"
        << "element vertex " << vertices.size()
        << "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar material\n"
        << "element face " << faces.size() << "\nproperty list uchar int vertex_indices\n"
        << "end_header\n";
    for (size_t i = 0; i < vertices.size(); ++i) {
      out.write(reinterpret_cast<const char*>(vertices[i].data()), 12);
      out.put(static_cast<char>(labels[i]));
    }
    for (const auto& f : faces) {
      out.put(3);
      out.write(reinterpret_cast<const char*>(f.data()), 12);
    }
    if (!out) throw InputError(path, "write error");
  });
}

}  // namespace gf::synth
