// The bounds every setting is held to, each with a physical meaning, and FieldCheck, the helper an
// Options struct's Check() uses to refuse a value outside its field's range with one line that
// names the field (DESIGN.md: bad configuration -> Check() false with a message).
//
// An upper bound says what a larger value would mean: a window larger than any image, more
// iterations than a frame's time allows, a depth no sensor measures. The bounds are generous
// (many times what any capture needs): they refuse nonsense, never a real choice.
//
// Usage, in a Check():
//   FieldCheck c(message);
//   c.In("pixel_step", pixel_step, 1, kMaxImageSidePx, kLargerThanAnyImage)
//       .Above("max_depth_m", max_depth_m, 0, kMaxDepthM, kFartherThanAnySensor)
//       .Require(max_depth_m > min_depth_m, "max_depth_m must be more than min_depth_m")
//       .Part("icp", icp);
//   return c.ok();
// The first refusal is kept, e.g. "normal_filter_px 30000 is larger than any image (at most
// 2048)"; a part's refusal is prefixed with its name ("icp.iterations[0] 2000000000 is more ...").
#pragma once

#include <string>
#include <vector>

namespace gf {

// Image side, pixels: no sensor GlassFusion reads gives a larger image (Kinect v1 640, RealSense
// D435 1280, Azure Kinect colour 4096). Bounds windows, filters, margins and pixel distances.
inline constexpr int kMaxImageSidePx = 4096;
// Pixels of the largest image: bounds per-image counts (features, inliers, samples, areas).
inline constexpr double kMaxImagePixels = static_cast<double>(kMaxImageSidePx) * kMaxImageSidePx;
// Levels of an image pyramid: halving a side of 4096 pixels 12 times leaves one pixel.
inline constexpr int kMaxPyramidLevels = 12;
// The smallest image GlassFusion works on, pixels: the image pyramid halves it three times and
// the normals' filter runs at half size, which leaves a few pixels each way at this size.
inline constexpr int kMinImageWidthPx = 32;
inline constexpr int kMinImageHeightPx = 24;
// Depth, metres: no RGB-D sensor measures farther (Kinect v1 about 8 m, RealSense D435 about
// 10 m). Bounds depth ranges and lengths measured in the camera (sigmas, gaps, noise).
inline constexpr double kMaxDepthM = 100;
// Distance, metres, across the scenes GlassFusion scans (rooms, a building): bounds distances
// between camera poses (baselines, jumps, proximity) and metric tolerances on them.
inline constexpr double kMaxSceneM = 1000;
// A relative depth difference (a fraction of the depth): 100 puts two depths a factor 101 apart,
// far beyond the span of any sensor's range (Kinect v1, 0.4-8 m: a factor 20).
inline constexpr double kMaxRelativeDepth = 100;
// An angle between two directions, degrees: a half turn at most.
inline constexpr double kMaxAngleDeg = 180;
// Iterations of an optimiser for one frame or pair: a Gauss-Newton step over a 640x480 image costs
// about a millisecond, so 1000 take a second, 30 frame periods at 30 frames/s.
inline constexpr int kMaxIterations = 1000;
// Frames of one capture: a whole day at 30 frames/s (2,592,000). Bounds counts of frames and
// keyframes (ages, windows, candidates) and confidences, which grow by at most one per frame.
inline constexpr int kMaxCaptureFrames = 30 * 60 * 60 * 24;
// Frames (or keyframes) held in memory at once: a 640x480 RGB-D frame with its masks and
// features takes about 3 MB, so 1024 of them about 3 GB.
inline constexpr int kMaxFramesInMemory = 1024;
// The largest grey level (or grey-level difference) of an 8-bit image.
inline constexpr double kMaxGreyLevel = 255;
// A threshold in standard deviations: a normal variable lies beyond 40 sigmas with a probability
// below the smallest double, so 1000 sigmas cut nothing that could be measured.
inline constexpr double kMaxSigmas = 1000;
// One cost term's weight relative to another: beyond a million the other term falls below the
// rounding of the single-precision images it is computed from (2^-23, about 1.2e-7).
inline constexpr double kMaxRelativeWeight = 1e6;

// What a value beyond each bound would be, for FieldCheck's messages.
inline constexpr const char* kLargerThanAnyImage = "is larger than any image";
inline constexpr const char* kMoreThanAnImagesPixels = "is more than an image's pixels";
inline constexpr const char* kFartherThanAnySensor = "is farther than any sensor measures";
inline constexpr const char* kLargerThanAnyScene = "is larger than any scene";
inline constexpr const char* kBeyondAnyDepthRange = "spans more than any sensor's depth range";
inline constexpr const char* kMoreThanAHalfTurn = "is more than a half turn";
inline constexpr const char* kMoreIterationsThanAFrameAllows =
    "is more iterations than a frame's time allows";
inline constexpr const char* kMoreFramesThanACapture = "is more frames than a day's capture";
inline constexpr const char* kMoreFramesThanMemory = "is more frames than memory holds";
inline constexpr const char* kBeyondGreyLevels = "is beyond 8-bit grey levels";
inline constexpr const char* kMoreSigmasThanMeasurable =
    "is more standard deviations than any "
    "measurement lies out";
inline constexpr const char* kOutweighsBeyondRounding =
    "makes the other term vanish below rounding";
inline constexpr const char* kMoreLevelsThanAnyPyramid = "is more levels than any image's pyramid";
inline constexpr const char* kMoreThanOne = "is more than one";

class FieldCheck {
 public:
  // The first refusal goes to *message (which may be null).
  explicit FieldCheck(std::string* message) : message_(message) {}

  // low <= value <= high. `beyond` completes "<field> <value> ..." for a value above high.
  FieldCheck& In(const char* field, double value, double low, double high, const char* beyond);
  // low < value <= high.
  FieldCheck& Above(const char* field, double value, double low, double high, const char* beyond);
  // In() for every element, named field[i]; an empty list is refused.
  FieldCheck& Each(const char* field, const std::vector<int>& values, int low, int high,
                   const char* beyond);
  // A condition on several fields; `problem` should start with the field it blames.
  FieldCheck& Require(bool condition, const std::string& problem);
  // The part's own Check(); its refusal is kept as "<name>.<its message>".
  template <typename Options>
  FieldCheck& Part(const char* name, const Options& part) {
    if (!ok_) return *this;
    std::string problem;
    if (!part.Check(&problem)) Refuse(std::string(name) + "." + problem);
    return *this;
  }

  bool ok() const { return ok_; }

 private:
  void Refuse(const std::string& problem);
  std::string* message_;
  bool ok_ = true;
};

// A number as FieldCheck writes it: whole numbers below 1e10 in full (357913941), others as
// printf's %g (1e+12, 0.0004).
std::string FormatNumber(double value);

}  // namespace gf
