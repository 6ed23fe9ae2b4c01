// The Kinect v1 model of the synthetic scenes: RenderFrame ray-casts a frame and simulates the
// sensor on every pixel (noise, quantisation, range, shadows, IR-failing materials, clear glass).
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core/utility.hpp>

#include "acquisition/depth.h"
#include "acquisition/errors.h"
#include "datasets/synth.h"
#include "acquisition/bounds.h"

namespace gf::synth {
namespace {

// Standard normal from two hashed uniforms (Box-Muller).
double HashGaussian(int x, int y, int frame, uint32_t seed) {
  const double u1 = std::max(1e-12, static_cast<double>(HashUniform(x, y, frame, seed)));
  const double u2 = HashUniform(x, y, frame, seed ^ 0xA5A5A5A5u);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

// The uniform draw of pixel (u, v) shared by its patch: the cell of a grid of spacing patch_px
// whose jittered centre is nearest (a Voronoi cell; 0: the pixel's own draw).
double PatchUniform(int u, int v, int frame, uint32_t seed, double patch_px) {
  if (!(patch_px > 0)) return HashUniform(u, v, frame, seed);
  const int cell_u = static_cast<int>(std::floor(u / patch_px)),
            cell_v = static_cast<int>(std::floor(v / patch_px));
  double best = std::numeric_limits<double>::max();
  int best_u = cell_u, best_v = cell_v;
  for (int j = cell_v - 1; j <= cell_v + 1; ++j)
    for (int i = cell_u - 1; i <= cell_u + 1; ++i) {
      const double x = (i + HashUniform(i, j, frame, seed ^ 0x3Cu)) * patch_px,
                   y = (j + HashUniform(i, j, frame, seed ^ 0x5Au)) * patch_px;
      const double d2 = (x - u) * (x - u) + (y - v) * (y - v);
      if (d2 < best) best = d2, best_u = i, best_v = j;
    }
  return HashUniform(best_u, best_v, frame, seed);
}

// What the Kinect gives for one pixel.
struct Reading {
  uint16_t raw = DepthConvention::kKinectNoReturn;
  uint8_t reason = static_cast<uint8_t>(HoleCode::kOutOfRange);
  GlassReading glass = GlassReading::kNone;
};

Reading Hole(HoleCode code) {
  Reading r;
  r.reason = static_cast<uint8_t>(code);
  return r;
}

// The sensor of one frame: the scene, its options and the projector's position in world.
struct Sensor {
  const Scene& scene;
  const KinectModelOptions& kinect;
  Eigen::Vector3d projector;
  double cos_grazing = 0;
  uint32_t noise_seed = 0;
  int frame = 0;
};

// A return from `point` (camera depth z metres, cosine of incidence `facing`) lit by the
// projector: too oblique, in shadow, or the depth with noise and 11-bit quantisation.
// light_through_glass: the projector's light passes clear glass on its way to the point.
Reading Measure(const Sensor& s, int u, int v, const Eigen::Vector3d& point, double z,
                double facing, bool light_through_glass) {
  if (facing < s.cos_grazing) return Hole(HoleCode::kNoReturn);
  const Eigen::Vector3d to_point = point - s.projector;
  const double distance = to_point.norm();
  Hit blocker;
  if (s.scene.Intersect(s.projector, to_point / distance, 1e-4, distance - 1e-3,
                        light_through_glass, &blocker))
    return Hole(HoleCode::kShadow);
  const double sigma = s.kinect.noise_a_m + s.kinect.noise_b_per_m * (z - 0.4) * (z - 0.4);
  const double noisy = z + sigma * HashGaussian(u, v, s.frame, s.noise_seed);
  Reading r;
  r.raw = DepthConvention::KinectV1Raw11Bit().FromMetres(noisy);
  r.reason = r.raw == DepthConvention::kKinectNoReturn ? static_cast<uint8_t>(HoleCode::kOutOfRange)
                                                       : static_cast<uint8_t>(HoleCode::kValid);
  return r;
}

// Clear glass (see KinectModelOptions): a return from the glass surface, a reading of the surface
// behind it (`behind`, found = false when the ray leaves the scene), or a hole.
Reading MeasureClearGlass(const Sensor& s, int u, int v, const Hit& glass, double glass_z,
                          const Eigen::Vector3d& dir, bool found, const Hit& behind,
                          double behind_z) {
  const KinectModelOptions& k = s.kinect;
  const double facing = std::max(0.0, -dir.dot(glass.normal));
  if (facing < s.cos_grazing) return Hole(HoleCode::kNoReturn);
  const double p_surface = k.glass_surface_probability * std::pow(facing, k.glass_surface_exponent);
  const double p_hole = k.glass_hole_probability * std::pow(facing, k.glass_hole_exponent);
  const double draw = PatchUniform(u, v, s.frame, s.noise_seed ^ 0x1Eu, k.glass_patch_px);
  if (draw < p_surface) {
    Reading r = Measure(s, u, v, glass.point, glass_z, facing, false);
    if (r.reason == static_cast<uint8_t>(HoleCode::kValid)) r.glass = GlassReading::kSurface;
    return r;
  }
  if (draw < p_surface + p_hole) return Hole(HoleCode::kNoReturn);
  if (!found) return Hole(HoleCode::kOutOfRange);
  if (FailsInfrared(s.scene.primitives()[behind.primitive].surface.material))
    return Hole(HoleCode::kNoReturn);
  const double z = behind_z + k.glass_through_offset_m +
                   k.glass_through_sigma_m * HashGaussian(u, v, s.frame, s.noise_seed ^ 0x7Eu);
  if (z < k.min_depth_m || z > k.max_depth_m) return Hole(HoleCode::kOutOfRange);
  Reading r = Measure(s, u, v, behind.point, z, -dir.dot(behind.normal), true);
  if (r.reason == static_cast<uint8_t>(HoleCode::kValid)) r.glass = GlassReading::kThrough;
  return r;
}

}  // namespace

bool KinectModelOptions::Check(std::string* message) const {
  // A power of cos(theta) beyond 100 is zero for any incidence but head-on; glass displaces the
  // depth read through it by centimetres, never a metre.
  constexpr double kSteepest = 100;
  constexpr double kMaxGlassOffsetM = 1;
  FieldCheck c(message);
  c.In("projector_baseline_m", projector_baseline_m, -kMaxSceneM, kMaxSceneM, kLargerThanAnyScene)
      .Above("min_depth_m", min_depth_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .Above("max_depth_m", max_depth_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .Require(max_depth_m > min_depth_m, "max_depth_m must be more than min_depth_m")
      .In("noise_a_m", noise_a_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .In("noise_b_per_m", noise_b_per_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .In("ir_return_probability", ir_return_probability, 0, 1, kMoreThanOne)
      .Above("grazing_angle_deg", grazing_angle_deg, 0, 90, "is beyond grazing incidence")
      .In("glass_surface_probability", glass_surface_probability, 0, 1, kMoreThanOne)
      .In("glass_hole_probability", glass_hole_probability, 0, 1, kMoreThanOne)
      .Require(glass_surface_probability + glass_hole_probability <= 1,
               "glass_surface_probability + glass_hole_probability must be at most 1")
      .In("glass_surface_exponent", glass_surface_exponent, 0, kSteepest, "is steeper than 100")
      .In("glass_hole_exponent", glass_hole_exponent, 0, kSteepest, "is steeper than 100")
      .In("glass_through_offset_m", glass_through_offset_m, -kMaxGlassOffsetM, kMaxGlassOffsetM,
          "is more than a metre")
      .In("glass_through_sigma_m", glass_through_sigma_m, 0, kMaxGlassOffsetM,
          "is more than a metre")
      .In("glass_patch_px", glass_patch_px, 0, kMaxImageSidePx, kLargerThanAnyImage);
  return c.ok();
}

KinectModelOptions KinectModelOptions::ClearGlassAsHoles() {
  KinectModelOptions o;
  o.glass_surface_probability = o.ir_return_probability;
  o.glass_hole_probability = 1.0 - o.ir_return_probability;
  o.glass_surface_exponent = o.glass_hole_exponent = 0.0;
  o.glass_patch_px = 0.0;
  return o;
}

namespace {

// One pixel's truth, colour and reading.
struct Pixel {
  Eigen::Vector3f bgr = Eigen::Vector3f::Zero();
  float true_z = 0.f, visible_z = 0.f;
  uint8_t label = kNoSurface;
  Reading reading;
};

Pixel RenderPixel(const Sensor& s, const Camera& camera, const SE3& world_from_camera, int u,
                  int v) {
  const Scene& scene = s.scene;
  // The ray through the pixel, through the lens when it has distortion (the same values as the
  // pinhole's (u - cx) / fx when it has none).
  const Eigen::Vector2d n = camera.UndistortPixel({u, v});
  const Eigen::Vector3d ray_camera(n.x(), n.y(), 1.0);
  const double ray_norm = ray_camera.norm();
  const Eigen::Vector3d dir = world_from_camera.RotationMatrix() * ray_camera / ray_norm;
  const Eigen::Vector3d origin = world_from_camera.translation();
  Pixel p;
  Hit first;
  if (!scene.Intersect(origin, dir, 1e-4, 1e3, false, &first)) return p;
  const Surface& surface = scene.primitives()[first.primitive].surface;
  p.label = static_cast<uint8_t>(surface.material);
  p.true_z = static_cast<float>(first.t / ray_norm);
  const bool clear = surface.material == Material::kClearGlass;
  // What the colour camera sees.
  Hit behind;
  bool found_behind = false;
  if (clear) {
    // The nearest surface that is not clear glass, searched from the camera rather than from just
    // past the glass, so that a surface touching the glass (the table under a bottle's base) is
    // not stepped over.
    found_behind = scene.Intersect(origin, dir, 1e-4, 1e3, true, &behind);
    if (found_behind) {
      p.visible_z = static_cast<float>(behind.t / ray_norm);
      p.bgr = 0.82f * scene.Shade(behind, dir) + 0.18f * surface.base_bgr;
    }
    const Eigen::Vector3d reflected = dir - 2.0 * dir.dot(first.normal) * first.normal;
    p.bgr += Eigen::Vector3f::Constant(
        0.5f *
        static_cast<float>(std::pow(std::max(0.0, reflected.dot(Eigen::Vector3d::UnitZ())), 60.0)));
  } else {
    p.visible_z = p.true_z;
    p.bgr = scene.Shade(first, dir);
  }
  // What the Kinect measures.
  const double z = p.true_z;
  if (z < s.kinect.min_depth_m || z > s.kinect.max_depth_m) {
    p.reading = Hole(HoleCode::kOutOfRange);
  } else if (clear) {
    p.reading = MeasureClearGlass(s, u, v, first, z, dir, found_behind, behind, p.visible_z);
  } else if (FailsInfrared(surface.material) &&
             HashUniform(u, v, s.frame, s.noise_seed ^ 0x1Eu) >= s.kinect.ir_return_probability) {
    p.reading = Hole(HoleCode::kNoReturn);
  } else {
    p.reading = Measure(s, u, v, first.point, z, -dir.dot(first.normal), false);
  }
  return p;
}

}  // namespace

SynthFrame RenderFrame(const Scene& scene, const Camera& camera, const SE3& world_from_camera,
                       const KinectModelOptions& kinect, uint32_t seed, int frame_index) {
  std::string problem;
  GF_CHECK(kinect.Check(&problem), problem);
  SynthFrame f;
  f.world_from_camera = world_from_camera;
  const int w = camera.width, h = camera.height;
  f.color.create(h, w, CV_8UC3);
  f.raw_disparity.create(h, w, CV_16UC1);
  f.true_depth.create(h, w, CV_32FC1);
  f.visible_depth.create(h, w, CV_32FC1);
  f.label.create(h, w, CV_8UC1);
  f.hole_reason.create(h, w, CV_8UC1);
  f.glass_reading.create(h, w, CV_8UC1);
  const Sensor sensor{scene,
                      kinect,
                      world_from_camera * Eigen::Vector3d(kinect.projector_baseline_m, 0, 0),
                      std::cos(kinect.grazing_angle_deg * M_PI / 180.0),
                      seed * 2654435761u + 17u,
                      frame_index};

  // Rows are independent and every random number is a hash of (pixel, frame, seed), so the
  // result does not depend on how OpenCV splits the rows between its worker threads.
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      for (int u = 0; u < w; ++u) {
        const Pixel p = RenderPixel(sensor, camera, world_from_camera, u, v);
        // Colour sensor: 8-bit with a little noise.
        cv::Vec3b& c = f.color.at<cv::Vec3b>(v, u);
        for (int k = 0; k < 3; ++k) {
          const double noise =
              1.5 * HashGaussian(u, v, frame_index * 3 + k, sensor.noise_seed ^ 0xC0u);
          c[k] = cv::saturate_cast<uint8_t>(255.0 * p.bgr[k] + noise);
        }
        f.raw_disparity.at<uint16_t>(v, u) = p.reading.raw;
        f.true_depth.at<float>(v, u) = p.true_z;
        f.visible_depth.at<float>(v, u) = p.visible_z;
        f.label.at<uint8_t>(v, u) = p.label;
        f.hole_reason.at<uint8_t>(v, u) = p.reading.reason;
        f.glass_reading.at<uint8_t>(v, u) = static_cast<uint8_t>(p.reading.glass);
      }
    }
  });
  return f;
}

ClearGlassStats& ClearGlassStats::operator+=(const ClearGlassStats& o) {
  pixels += o.pixels;
  holes += o.holes;
  through += o.through;
  surface += o.surface;
  return *this;
}

ClearGlassStats CountClearGlass(const SynthFrame& f) {
  ClearGlassStats c;
  const uint8_t clear = static_cast<uint8_t>(Material::kClearGlass);
  for (int v = 0; v < f.label.rows; ++v)
    for (int u = 0; u < f.label.cols; ++u) {
      if (f.label.at<uint8_t>(v, u) != clear) continue;
      ++c.pixels;
      c.holes += f.raw_disparity.at<uint16_t>(v, u) == DepthConvention::kKinectNoReturn;
      const auto g = static_cast<GlassReading>(f.glass_reading.at<uint8_t>(v, u));
      c.through += g == GlassReading::kThrough;
      c.surface += g == GlassReading::kSurface;
    }
  return c;
}

}  // namespace gf::synth
