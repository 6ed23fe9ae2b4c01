// The synthetic Kinect v1 dataset generator behind `glassfusion synth` and `make demo`.
//
// Renders a Scene along a handheld-like trajectory and simulates a Kinect v1:
//  - 640x480, depth registered to colour (one pinhole camera, fx = fy = 525);
//  - a projector 7.5 cm along the camera's +x axis: surface points it cannot light are shadows;
//  - depth noise growing with the square of depth, sigma(z) = 0.0012 + 0.0019 (z - 0.4)^2 metres
//    (Nguyen, Izadi, Lovell, 3DIMPVT 2012), then quantisation through the 11-bit raw disparity
//    value (one raw step is about 1/8 pixel of disparity, DepthConvention::KinectV1Raw11Bit);
//  - range 0.5-4.5 m; raw value 2047 on glossy, dark and textured-glass surfaces (a small share of
//    their pixels still return, as real sensors do), out of range, in projector shadow, and at
//    grazing angles;
//  - clear glass as real sensors see it (measured on RealSense D435 frames of clear objects,
//    tests/glass_sensor_stats.py): a pixel reads the surface behind the glass, the glass surface
//    itself (mostly where it faces the camera), or nothing (KinectModelOptions::glass_*).
//
// Output folder (written under a temporary name, renamed when complete):
//   rgb/ depth/ rgb.txt depth.txt camera.json   a TUM RGB-D folder (16-bit depth, 5000 per metre)
//   groundtruth.txt                             world_from_camera per frame (TUM format)
//   raw/                                        fakenect recording: INDEX.txt, d-*.pgm (11-bit raw,
//                                               little-endian), r-*.ppm, camera.json
//   gt/depth/<ts>.png                           true depth of the first surface hit (glass too)
//   gt/visible_depth/<ts>.png                   depth of what colour sees (through clear glass)
//   gt/label/<ts>.png                           material of the first hit (synth::Material,
//                                               255 none)
//   gt/holes/<ts>.png                           why the sensor has no depth (HoleCode; 0 where
//                                               clear glass reads the surface behind it)
//   scene.ply                                   the scene as a triangle mesh
//   synth.json                                  scene, seed, options, generation time, and
//                                               clear_glass_sensor: shares of clear-glass pixels
//                                               that are holes / read behind / read the glass
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"
#include "datasets/scene.h"

namespace gf::synth {

struct KinectModelOptions {
  double projector_baseline_m = 0.075;  // projector along the camera's +x axis, metres
  double min_depth_m = 0.5;             // nearer surfaces read 2047, metres
  double max_depth_m = 4.5;             // farther surfaces read 2047, metres
  double noise_a_m = 0.0012;            // sigma(z) = a + b (z - 0.4)^2, metres
  double noise_b_per_m = 0.0019;
  double ir_return_probability = 0.03;  // share of IR-failing pixels that still return depth
  double grazing_angle_deg = 82.0;      // steeper incidence drops the return
  // Clear glass (Material::kClearGlass). Each pixel whose first surface is clear glass (in range,
  // not beyond grazing_angle_deg) draws one outcome. With theta the angle between the glass's
  // normal and the ray (0 = the glass faces the camera):
  //   P(glass surface) = glass_surface_probability * cos(theta)^glass_surface_exponent
  //   P(hole)          = glass_hole_probability * cos(theta)^glass_hole_exponent
  //   P(through)       = the rest: the light passes the glass and the sensor reads what is behind.
  // Both glass-surface returns and holes are most common where the glass faces the camera;
  // oblique glass is mostly seen through. A glass-surface return is
  // measured like any surface (noise, shadow). A reading through the glass gives the depth of the
  // first surface behind it that is not clear glass (what colour sees, SynthFrame::visible_depth),
  // moved by refraction: plus glass_through_offset_m plus a Gaussian of glass_through_sigma_m,
  // then the usual noise; it is a hole where that surface fails infrared, lies out of range, at a
  // grazing angle or in the projector's shadow. Fitted to RealSense D435 frames of clear objects
  // (tests/glass_sensor_stats.py).
  double glass_surface_probability = 0.41;  // glass-surface returns at head-on incidence, 0-1
  double glass_surface_exponent = 2.0;      // their fall-off with cos(theta), >= 0
  double glass_hole_probability = 0.55;     // holes at head-on incidence, 0-1
  double glass_hole_exponent = 1.5;         // their fall-off with cos(theta), >= 0
  double glass_through_offset_m = 0.012;    // mean extra depth of readings through glass, metres
  double glass_through_sigma_m = 0.006;     // standard deviation of that extra depth, metres
  // The outcome is drawn per patch of pixels, not per pixel: a depth camera matches windows of
  // its pattern, so neighbouring pixels on glass share their fate (on the real D435 frames a pixel
  // 8 px from a glass-surface return is one too with probability 0.62-0.64, 4.6 px in a Kinect
  // image; tests/glass_sensor_stats.py). Patches are the cells of a jittered grid of this
  // spacing in pixels (nearest jittered centre, so their shapes vary), drawn anew every frame;
  // 0: every pixel draws its own.
  double glass_patch_px = 24.0;
  bool Check(std::string* message = nullptr) const;
  // A sensor that treats clear glass like the other IR-failing materials: a hole but for
  // ir_return_probability of glass-surface returns, at any angle (no reading through it), drawn
  // per pixel. For tests of what the fill does with large clear-glass holes.
  static KinectModelOptions ClearGlassAsHoles();
};

// How the camera moves, always looking at the scene's focus.
enum class Motion {
  kOrbit,     // sideways around it
  kVertical,  // up, or up and down when looping
  kDiagonal,  // both at once
  kForward,   // towards it
};
// "orbit", "vertical", "diagonal", "forward"; false for anything else.
bool ParseMotion(const std::string& text, Motion* motion);
const char* MotionName(Motion motion);

struct SynthOptions {
  std::string scene = "glass-table";  // Scene::Names()
  int frames = 60;                    // frames to render
  uint32_t seed = 1;                  // scene textures, trajectory jitter and sensor noise
  bool loop = false;                  // the trajectory comes back to its start
  // How the camera moves; every motion covers the same distance per frame.
  Motion motion = Motion::kOrbit;
  double fps = 30.0;               // timestamps step, frames per second
  double degrees_per_frame = 0.6;  // speed: this arc of the orbit per frame (about 1.6 cm)
  double jitter_m = 0.015;         // handheld wobble of the camera position, metres
  KinectModelOptions kinect;
  bool Check(std::string* message = nullptr) const;
};

// What the sensor read on a clear-glass pixel (SynthFrame::glass_reading).
enum class GlassReading : uint8_t {
  kNone = 0,     // not clear glass, or a hole
  kSurface = 1,  // the glass surface itself (a specular return)
  kThrough = 2,  // the surface behind the glass
};

// One rendered frame before it is written.
struct SynthFrame {
  double timestamp = 0;
  SE3 world_from_camera;
  cv::Mat color;          // CV_8UC3 BGR
  cv::Mat raw_disparity;  // CV_16UC1 Kinect v1 11-bit raw, 2047 = no return
  cv::Mat true_depth;     // CV_32FC1 metres to the first surface (0 = none)
  cv::Mat visible_depth;  // CV_32FC1 metres to the first surface that is not clear glass
  cv::Mat label;          // CV_8UC1 Material of the first hit, kNoSurface where none
  cv::Mat hole_reason;    // CV_8UC1 HoleCode: why raw_disparity is 2047
  // CV_8UC1 GlassReading: on clear glass, whether the depth read is the glass's own or the
  // surface's behind it. Clear-glass pixels keep their label (the truth stays the glass's own
  // surface, true_depth); those read through it are valid readings, not holes.
  cv::Mat glass_reading;
};

// What the sensor gave on the clear-glass pixels of one or more frames.
struct ClearGlassStats {
  size_t pixels = 0;   // clear glass is the first surface
  size_t holes = 0;    // raw 2047 (any HoleCode)
  size_t through = 0;  // read the surface behind the glass
  size_t surface = 0;  // read the glass surface
  double Share(size_t n) const { return pixels ? static_cast<double>(n) / pixels : 0.0; }
  ClearGlassStats& operator+=(const ClearGlassStats& o);
};
ClearGlassStats CountClearGlass(const SynthFrame& frame);

// Whether a depth filled in on a clear-glass pixel is "reported as glass": within 2% of the
// glass's own depth (true_depth) and more than 5% off the background the colour camera sees
// through it (visible_depth); where the two are within a few percent they cannot be told apart.
// Stereo hole filling should give the background: the goal is no such pixel.
inline bool AtClearGlassDepth(double fill, double glass, double background) {
  return std::abs(fill - glass) < 0.02 * glass && std::abs(fill - background) > 0.05 * background;
}

// The camera every synthetic dataset uses (640x480, fx = fy = 525, no distortion).
Camera SynthCamera();
// Its camera.json: depth in units of 1/5000 m, and a global shutter (every pixel of a frame is
// rendered at the frame's pose: depth_readout_s 0).
CameraFile SynthCameraFile();
// world_from_camera of frame i.
std::vector<SE3> MakeTrajectory(const Scene& scene, const SynthOptions& options);
// Renders one frame through `camera` (its lens distortion too); frame_index seeds its sensor noise.
SynthFrame RenderFrame(const Scene& scene, const Camera& camera, const SE3& world_from_camera,
                       const KinectModelOptions& kinect, uint32_t seed, int frame_index);

// The frame as a frame source delivers it: colour, and metric depth with its hole mask converted
// from the raw disparity exactly as a recorded raw Kinect frame is, projector shadows classified
// (timestamps left to the caller), and the median depth of its returns.
RgbdFrame ToRgbdFrame(const SynthFrame& frame, int index);

struct SynthSummary {
  int frames = 0;
  double seconds_per_frame = 0;  // render + write, wall clock
  double hole_fraction = 0;      // share of sensor pixels at 2047
  ClearGlassStats clear_glass;   // what the sensor read on clear glass, all frames
  std::string BriefReport() const;
};

// Generates the whole folder. progress(done, total) after each frame. Throws InputError when
// out_dir exists and is not empty, or on write errors (nothing is left behind).
SynthSummary GenerateDataset(const SynthOptions& options, const std::string& out_dir,
                             const std::function<void(int, int)>& progress = {});

}  // namespace gf::synth
