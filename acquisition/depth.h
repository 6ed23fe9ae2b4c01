// Depth conventions, conversion of raw depth images to metres, and hole masks.
//
// Sensors store depth in different raw units; GlassFusion converts every depth image to metres
// (CV_32F, 0 = no depth) plus a hole mask (CV_8U, HoleCode per pixel) at the edge.
//
//  - Millimetres():       raw / 1000 = metres, 0 = no return (ICL-NUIM, Redwood, OpenNI2).
//  - ScaledUnits(s):      raw / s = metres, 0 = no return (TUM: s = 5000).
//  - KinectV1Raw11Bit():  raw 11-bit disparity of the Kinect v1 (libfreenect FREENECT_DEPTH_11BIT,
//                         NYU raw PGMs). 2047 (0x7FF) = no return. Metres by the standard model of
//                         N. Burrus (Kinect calibration, 2011):
//                             depth_m = 1 / (kA * raw + kB),  kA = -0.0030711016, kB = 3.3309495161
//                         valid for raw below ~1084 (depth grows without bound there).
//
// Note that 2047 is a hole only for raw disparity: in a millimetre stream 2047 means 2.047 m.
//
// Usage:
//   cv::Mat depth_m, holes;
//   gf::ConvertDepth(raw16, gf::DepthConvention::ScaledUnits(5000), {}, &depth_m, &holes);
//   gf::HoleStats s = gf::CountHoles(holes);  // s.Fraction()
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace gf {

// Per-pixel hole classes, the values of keyframes/<ts>.hole_mask.png (DESIGN.md).
enum class HoleCode : uint8_t {
  kValid = 0,       // the sensor measured this pixel
  kNoReturn = 1,    // no return (0 / 0x7FF) inside the sensor's range: glass, specular, dark
  kOutOfRange = 2,  // measured value outside [min_depth_m, max_depth_m]
  kShadow = 3,      // projector occlusion shadow at a depth discontinuity
};

// Where a pixel's depth came from: the `source` field of map.ply and of every filled depth image.
// kCarried: stereo depth of earlier keyframes carried into this one (fill/fill_carry.h).
// kTransparent: a surface the sensor both reads and sees through (clear glass), found by the
// map's fusion (surfels/fusion.h, FusionOptions::glass). (3 was taken by the COLMAP fill first.)
enum class DepthSource : uint8_t {
  kNone = 0,
  kSensor = 1,
  kStereo = 2,
  kColmap = 3,
  kCarried = 4,
  kTransparent = 5,
};
inline constexpr size_t kDepthSources = 6;  // the values of DepthSource

class DepthConvention {
 public:
  enum class Kind { kMillimetres, kScaledUnits, kKinectV1Raw11Bit };

  // Kinect v1 disparity model constants (see the file comment).
  static constexpr double kKinectA = -0.0030711016;   // 1/metres per disparity unit
  static constexpr double kKinectB = 3.3309495161;    // 1/metres
  static constexpr uint16_t kKinectNoReturn = 0x7FF;  // 2047

  static DepthConvention Millimetres() { return DepthConvention(Kind::kMillimetres, 1000.0); }
  static DepthConvention ScaledUnits(double units_per_metre);
  static DepthConvention KinectV1Raw11Bit() { return DepthConvention(Kind::kKinectV1Raw11Bit, 0); }
  // From a camera.json depth_scale: 1000 -> Millimetres(), otherwise ScaledUnits(scale).
  static DepthConvention FromDepthScale(double units_per_metre);

  Kind kind() const { return kind_; }
  // Raw units per metre for linear conventions; 0 for Kinect raw disparity.
  double units_per_metre() const { return units_per_metre_; }
  // "millimetres", "scaled_units(5000)", "kinect_v1_raw_11bit".
  std::string Name() const;

  // Raw value that means "no measurement": 0, or 2047 for Kinect raw disparity.
  uint16_t NoReturnValue() const;
  bool IsNoReturn(uint16_t raw) const;
  // Metres for a raw value; 0 for the no-return value and for raw values the model cannot map.
  double ToMetres(uint16_t raw) const;
  // Raw value for a depth in metres (rounded); NoReturnValue() when depth is not representable.
  uint16_t FromMetres(double metres) const;
  // Empty when the raw image fits the convention, else a one-line problem, e.g. values above
  // 2047 in a Kinect raw disparity image (which is then millimetres, not disparity).
  std::string ValidateRaw(const cv::Mat& raw) const;

  bool operator==(const DepthConvention& o) const {
    return kind_ == o.kind_ && units_per_metre_ == o.units_per_metre_;
  }

 private:
  DepthConvention(Kind kind, double units_per_metre)
      : kind_(kind), units_per_metre_(units_per_metre) {}
  Kind kind_;
  double units_per_metre_;
};

struct DepthConversionOptions {
  double min_depth_m = 0.2;   // nearer measurements are classed out of range, metres
  double max_depth_m = 12.0;  // farther measurements are classed out of range, metres
  bool Check(std::string* message = nullptr) const;
};

// raw: CV_16UC1. depth_m: CV_32FC1 metres, 0 where there is a hole. hole_mask: CV_8UC1 HoleCode
// (kValid, kNoReturn or kOutOfRange; shadows are classified later, where geometry is known).
// Either output may be null. Throws std::logic_error when raw is not CV_16UC1.
void ConvertDepth(const cv::Mat& raw, const DepthConvention& convention,
                  const DepthConversionOptions& options, cv::Mat* depth_m, cv::Mat* hole_mask);

// The median depth, in metres, of a raw depth image's returns (every step-th pixel each way),
// before any range limit; 0 when it has none. A depth scale that is off by a factor moves it by
// that factor.
double MedianReturnDepth(const cv::Mat& raw, const DepthConvention& convention, int step = 4);

// Indoor RGB-D captures put the median return within these bounds (Kinect-class sensors measure
// 0.4-8 m): a median outside them almost certainly means a wrong depth_scale.
constexpr double kPlausibleMedianDepthMinM = 0.3;
constexpr double kPlausibleMedianDepthMaxM = 10.0;
// Empty when median_m (> 0) lies within those bounds, else a one-line problem naming the
// convention and the scale that would fix it.
std::string DepthScaleProblem(double median_m, const DepthConvention& convention);

// Metric depth (CV_32F, 0 = none) back to raw units, e.g. for writing a TUM-format PNG.
cv::Mat DepthToRaw(const cv::Mat& depth_m, const DepthConvention& convention);

// Projector occlusion shadows. A structured-light sensor sees depth only where its projector's
// pattern lands; next to a foreground edge, the background strip hidden from the projector is a
// hole on the side away from the projector, as wide as the parallax of the two depths:
//     width_px = fx * |baseline| * (1/z_near - 1/z_far).
// Kinect v1: the projector sits 7.5 cm along the depth camera's +x axis, so shadows fall on the
// left (-u) side of foreground objects.
struct ShadowOptions {
  double projector_baseline_m =
      0.075;                        // projector position along the depth camera's x axis, metres
  double min_relative_jump = 0.05;  // far side must be this much deeper than the near side
  double width_tolerance_px = 2.0;  // a run may exceed the predicted width by this, pixels
  // Continue shadows into the rows above and below where the near surface is a no-return surface
  // itself (its shadow and its own pixels form one run).
  bool continue_vertically = true;
  bool Check(std::string* message = nullptr) const;
};

// Reclassifies kNoReturn runs along image rows as kShadow where a run lies between a far surface on
// the side away from the projector and a near surface on the projector's side, and is no wider than
// the shadow that depth step predicts; with continue_vertically, such shadows are then continued
// into neighbouring rows where the near surface returns nothing itself (the shadow and that
// surface form one run there). depth_m and hole_mask are in the depth camera's image;
// fx is the depth camera's focal length in pixels. Returns the number of pixels reclassified.
size_t ClassifyShadows(const cv::Mat& depth_m, double fx, const ShadowOptions& options,
                       cv::Mat* hole_mask);

struct HoleStats {
  size_t pixels = 0;
  size_t no_return = 0;
  size_t out_of_range = 0;
  size_t shadow = 0;
  size_t holes() const { return no_return + out_of_range + shadow; }
  double Fraction() const { return pixels ? static_cast<double>(holes()) / pixels : 0.0; }
  HoleStats& operator+=(const HoleStats& o);
};
HoleStats CountHoles(const cv::Mat& hole_mask);

// The measured depths (> 0) of every step-th pixel in each direction of a metric depth image
// (CV_32F), sorted ascending: a cheap basis for a frame's depth percentiles.
std::vector<float> SortedDepthSample(const cv::Mat& depth_m, int step);

}  // namespace gf
