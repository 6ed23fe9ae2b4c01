#include "acquisition/depth.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <vector>

#include "acquisition/errors.h"
#include "acquisition/bounds.h"

namespace gf {

DepthConvention DepthConvention::ScaledUnits(double units_per_metre) {
  GF_CHECK(units_per_metre > 0 && std::isfinite(units_per_metre),
           "depth scale must be positive units per metre");
  return DepthConvention(Kind::kScaledUnits, units_per_metre);
}

DepthConvention DepthConvention::FromDepthScale(double units_per_metre) {
  return units_per_metre == 1000.0 ? Millimetres() : ScaledUnits(units_per_metre);
}

std::string DepthConvention::Name() const {
  switch (kind_) {
    case Kind::kMillimetres:
      return "millimetres";
    case Kind::kScaledUnits: {
      std::ostringstream s;
      s << "scaled_units(" << units_per_metre_ << ")";
      return s.str();
    }
    case Kind::kKinectV1Raw11Bit:
      return "kinect_v1_raw_11bit";
  }
  return "unknown";
}

uint16_t DepthConvention::NoReturnValue() const {
  return kind_ == Kind::kKinectV1Raw11Bit ? kKinectNoReturn : 0;
}

bool DepthConvention::IsNoReturn(uint16_t raw) const {
  if (kind_ == Kind::kKinectV1Raw11Bit) return raw >= kKinectNoReturn;
  return raw == 0;
}

double DepthConvention::ToMetres(uint16_t raw) const {
  if (IsNoReturn(raw)) return 0.0;
  if (kind_ == Kind::kKinectV1Raw11Bit) {
    const double inverse_depth = kKinectA * raw + kKinectB;
    return inverse_depth > 0 ? 1.0 / inverse_depth : 0.0;
  }
  return raw / units_per_metre_;
}

uint16_t DepthConvention::FromMetres(double metres) const {
  if (!(metres > 0) || !std::isfinite(metres)) return NoReturnValue();
  if (kind_ == Kind::kKinectV1Raw11Bit) {
    const double raw = std::round((1.0 / metres - kKinectB) / kKinectA);
    // Past the model's asymptote (raw ~1084.6) a disparity value maps to no positive depth.
    if (raw < 0 || raw >= kKinectNoReturn || kKinectA * raw + kKinectB <= 0) return NoReturnValue();
    return static_cast<uint16_t>(raw);
  }
  const double raw = std::round(metres * units_per_metre_);
  if (raw < 1 || raw > 65535) return NoReturnValue();
  return static_cast<uint16_t>(raw);
}

std::string DepthConvention::ValidateRaw(const cv::Mat& raw) const {
  if (raw.empty()) return "empty depth image";
  if (raw.type() != CV_16UC1) return "depth image must be single-channel 16-bit";
  if (kind_ == Kind::kKinectV1Raw11Bit) {
    double max_value = 0;
    cv::minMaxLoc(raw, nullptr, &max_value);
    if (max_value > kKinectNoReturn) {
      std::ostringstream s;
      s << "values up to " << max_value
        << " exceed 2047: not Kinect v1 11-bit disparity (millimetres? byte order?)";
      return s.str();
    }
  }
  return {};
}

bool DepthConversionOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.In("min_depth_m", min_depth_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .Above("max_depth_m", max_depth_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .Require(max_depth_m > min_depth_m, "max_depth_m must be more than min_depth_m");
  return c.ok();
}

double MedianReturnDepth(const cv::Mat& raw, const DepthConvention& convention, int step) {
  GF_CHECK(raw.type() == CV_16UC1 && step >= 1, "raw depth must be CV_16UC1, step >= 1");
  std::vector<double> metres;
  for (int y = 0; y < raw.rows; y += step) {
    const uint16_t* row = raw.ptr<uint16_t>(y);
    for (int x = 0; x < raw.cols; x += step) {
      const double m = convention.ToMetres(row[x]);
      if (m > 0) metres.push_back(m);
    }
  }
  if (metres.empty()) return 0.0;
  std::nth_element(metres.begin(), metres.begin() + metres.size() / 2, metres.end());
  return metres[metres.size() / 2];
}

std::string DepthScaleProblem(double median_m, const DepthConvention& convention) {
  if (!(median_m > 0) ||
      (median_m >= kPlausibleMedianDepthMinM && median_m <= kPlausibleMedianDepthMaxM))
    return "";
  std::ostringstream s;
  s.precision(3);
  s << "the median depth is " << median_m << " m with depth " << convention.Name()
    << ", outside the " << kPlausibleMedianDepthMinM << "-" << kPlausibleMedianDepthMaxM
    << " m of indoor captures";
  if (convention.units_per_metre() > 0) {
    std::ostringstream scale;
    scale << std::fixed << std::setprecision(0) << convention.units_per_metre();
    s << ": is depth_scale " << scale.str()
      << " right? (raw depth units per metre: TUM uses 5000, millimetre streams 1000)";
  }
  return s.str();
}

void ConvertDepth(const cv::Mat& raw, const DepthConvention& convention,
                  const DepthConversionOptions& options, cv::Mat* depth_m, cv::Mat* hole_mask) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  GF_CHECK(raw.type() == CV_16UC1, "raw depth must be CV_16UC1");
  // One lookup table of 65536 entries makes conversion a single pass for any convention.
  std::vector<float> metres(65536);
  std::vector<uint8_t> code(65536);
  for (int v = 0; v < 65536; ++v) {
    const uint16_t r = static_cast<uint16_t>(v);
    const double m = convention.ToMetres(r);
    if (convention.IsNoReturn(r)) {
      code[v] = static_cast<uint8_t>(HoleCode::kNoReturn);
      metres[v] = 0.f;
    } else if (!(m >= options.min_depth_m && m <= options.max_depth_m)) {
      code[v] = static_cast<uint8_t>(HoleCode::kOutOfRange);
      metres[v] = 0.f;
    } else {
      code[v] = static_cast<uint8_t>(HoleCode::kValid);
      metres[v] = static_cast<float>(m);
    }
  }
  if (depth_m) depth_m->create(raw.size(), CV_32FC1);
  if (hole_mask) hole_mask->create(raw.size(), CV_8UC1);
  for (int y = 0; y < raw.rows; ++y) {
    const uint16_t* in = raw.ptr<uint16_t>(y);
    float* d = depth_m ? depth_m->ptr<float>(y) : nullptr;
    uint8_t* h = hole_mask ? hole_mask->ptr<uint8_t>(y) : nullptr;
    for (int x = 0; x < raw.cols; ++x) {
      if (d) d[x] = metres[in[x]];
      if (h) h[x] = code[in[x]];
    }
  }
}

cv::Mat DepthToRaw(const cv::Mat& depth_m, const DepthConvention& convention) {
  GF_CHECK(depth_m.type() == CV_32FC1, "metric depth must be CV_32FC1");
  cv::Mat raw(depth_m.size(), CV_16UC1);
  for (int y = 0; y < depth_m.rows; ++y) {
    const float* d = depth_m.ptr<float>(y);
    uint16_t* r = raw.ptr<uint16_t>(y);
    for (int x = 0; x < depth_m.cols; ++x) r[x] = convention.FromMetres(d[x]);
  }
  return raw;
}

bool ShadowOptions::Check(std::string* message) const {
  // The baseline is signed (the projector's side of the camera).
  FieldCheck c(message);
  c.Above("min_relative_jump", min_relative_jump, 0, kMaxRelativeDepth, kBeyondAnyDepthRange)
      .In("width_tolerance_px", width_tolerance_px, 0, kMaxImageSidePx, kLargerThanAnyImage)
      .In("projector_baseline_m", projector_baseline_m, -kMaxSceneM, kMaxSceneM,
          kLargerThanAnyScene);
  return c.ok();
}

namespace {

// The shadow of an edge continues along the edge. Where the near surface is itself a no-return
// surface (clear glass, a dark object), its shadow and its own pixels form one no-return run that
// the row test cannot split; the part of such a run on the far side, next to a shadow run of the
// row above or below that starts at the same column beside the same far depth, is marked as
// shadow as wide as that neighbour's. Down the image, then up.
size_t ContinueShadowsVertically(const cv::Mat& depth_m, const ShadowOptions& options,
                                 cv::Mat* hole_mask) {
  const uint8_t no_return = static_cast<uint8_t>(HoleCode::kNoReturn);
  const uint8_t shadow = static_cast<uint8_t>(HoleCode::kShadow);
  const bool far_on_left = options.projector_baseline_m > 0;
  const int dir = far_on_left ? 1 : -1;  // away from the far side
  const int cols = depth_m.cols;
  size_t marked = 0;
  // Row y, continuing the shadows of row from_y. x is a run's first pixel next to the far surface
  // (far_x); the run extends from x away from the far side (dir).
  auto step = [&](int y, int from_y) {
    const float* d = depth_m.ptr<float>(y);
    const float* d_from = depth_m.ptr<float>(from_y);
    uint8_t* h = hole_mask->ptr<uint8_t>(y);
    const uint8_t* h_from = hole_mask->ptr<uint8_t>(from_y);
    for (int x = 1; x + 1 < cols; ++x) {
      const int far_x = x - dir;
      if (h[x] != no_return || h[far_x] != 0 || !(d[far_x] > 0)) continue;
      // A shadow run in the neighbouring row beside the same far surface, starting within a pixel.
      int width = 0;
      for (int dx = -1; dx <= 1 && width == 0; ++dx) {
        const int sx = x + dx, sfar = far_x + dx;
        if (sx < 1 || sx + 1 >= cols || sfar < 0 || sfar >= cols) continue;
        if (h_from[sx] != shadow || h_from[sfar] != 0 || !(d_from[sfar] > 0)) continue;
        if (std::abs(d_from[sfar] - d[far_x]) > options.min_relative_jump * d[far_x]) continue;
        for (int i = sx; i >= 0 && i < cols && h_from[i] == shadow; i += dir) ++width;
      }
      // Mark as much of this row's no-return run, up to that width, as shadow; a run no wider
      // than that is left to the row test (it had a measured near side, or none at all).
      int length = 0;
      for (int i = x; i >= 0 && i < cols && h[i] == no_return; i += dir) ++length;
      if (width == 0 || length <= width) continue;
      for (int i = 0; i < width; ++i) h[x + i * dir] = shadow;
      marked += width;
    }
  };
  for (int y = 1; y < depth_m.rows; ++y) step(y, y - 1);
  for (int y = depth_m.rows - 2; y >= 0; --y) step(y, y + 1);
  return marked;
}

}  // namespace

size_t ClassifyShadows(const cv::Mat& depth_m, double fx, const ShadowOptions& options,
                       cv::Mat* hole_mask) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  GF_CHECK(depth_m.type() == CV_32FC1 && hole_mask && hole_mask->type() == CV_8UC1 &&
               hole_mask->size() == depth_m.size(),
           "need CV_32F depth and a CV_8U hole mask of the same size");
  if (options.projector_baseline_m == 0) return 0;
  const uint8_t no_return = static_cast<uint8_t>(HoleCode::kNoReturn);
  const uint8_t shadow = static_cast<uint8_t>(HoleCode::kShadow);
  const double baseline = std::abs(options.projector_baseline_m);
  // Projector on +x: the far surface is on the left of the run, the near one on the right.
  const bool far_on_left = options.projector_baseline_m > 0;
  size_t marked = 0;
  for (int y = 0; y < depth_m.rows; ++y) {
    const float* d = depth_m.ptr<float>(y);
    uint8_t* h = hole_mask->ptr<uint8_t>(y);
    int x = 0;
    while (x < depth_m.cols) {
      if (h[x] != no_return) {
        ++x;
        continue;
      }
      const int start = x;
      while (x < depth_m.cols && h[x] == no_return) ++x;
      const int end = x;                                // run is [start, end)
      if (start == 0 || end == depth_m.cols) continue;  // touches the border: no two sides
      const float left = d[start - 1], right = d[end];
      if (!(left > 0) || !(right > 0)) continue;  // bounded by another kind of hole
      const double z_far = far_on_left ? left : right;
      const double z_near = far_on_left ? right : left;
      if (z_far < z_near * (1.0 + options.min_relative_jump)) continue;
      const double predicted = fx * baseline * (1.0 / z_near - 1.0 / z_far);
      if (end - start > predicted + options.width_tolerance_px) continue;
      for (int i = start; i < end; ++i) h[i] = shadow;
      marked += end - start;
    }
  }
  if (options.continue_vertically) marked += ContinueShadowsVertically(depth_m, options, hole_mask);
  return marked;
}

HoleStats& HoleStats::operator+=(const HoleStats& o) {
  pixels += o.pixels;
  no_return += o.no_return;
  out_of_range += o.out_of_range;
  shadow += o.shadow;
  return *this;
}

std::vector<float> SortedDepthSample(const cv::Mat& depth_m, int step) {
  GF_CHECK(depth_m.type() == CV_32FC1 && step >= 1, "need CV_32F depth and step >= 1");
  std::vector<float> sample;
  for (int y = 0; y < depth_m.rows; y += step)
    for (int x = 0; x < depth_m.cols; x += step)
      if (depth_m.at<float>(y, x) > 0) sample.push_back(depth_m.at<float>(y, x));
  std::sort(sample.begin(), sample.end());
  return sample;
}

HoleStats CountHoles(const cv::Mat& hole_mask) {
  GF_CHECK(hole_mask.type() == CV_8UC1, "hole mask must be CV_8UC1");
  HoleStats s;
  s.pixels = hole_mask.total();
  for (int y = 0; y < hole_mask.rows; ++y) {
    const uint8_t* h = hole_mask.ptr<uint8_t>(y);
    for (int x = 0; x < hole_mask.cols; ++x) {
      switch (static_cast<HoleCode>(h[x])) {
        case HoleCode::kNoReturn:
          ++s.no_return;
          break;
        case HoleCode::kOutOfRange:
          ++s.out_of_range;
          break;
        case HoleCode::kShadow:
          ++s.shadow;
          break;
        default:
          break;
      }
    }
  }
  return s;
}

}  // namespace gf
