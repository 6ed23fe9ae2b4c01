#include "fill/fill_validation.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>

#include "acquisition/bounds.h"
#include "acquisition/depth.h"
#include "acquisition/stats.h"

namespace gf {
namespace {

// The ring verdicts of one candidate: per hole, and per piece of a hole (the hole cut by a grid
// of ring_cell_px cells; a piece with enough ring samples of its own is judged by them, others by
// the hole's).
class RingVerdicts {
 public:
  RingVerdicts(const Holes& holes, const cv::Size& size, const ValidationOptions& options)
      : holes_(holes), options_(options) {
    cell_ = options.ring_cell_px > 0 ? options.ring_cell_px : std::max(size.width, size.height);
    cells_x_ = (size.width + cell_ - 1) / cell_;
    cells_ = static_cast<size_t>(cells_x_) * ((size.height + cell_ - 1) / cell_);
    // Entries [0, holes): whole holes; [holes, holes + holes * cells): pieces.
    errors_.resize(holes.count + holes.count * cells_);
    ratios_.resize(errors_.size());
  }
  void AddRingSample(int x, int y, float relative_error, float sensor_over_candidate) {
    const int label = holes_.labels.at<int>(y, x);
    for (size_t id : {static_cast<size_t>(label), Piece(x, y, label)}) {
      errors_[id].push_back(relative_error);
      ratios_[id].push_back(sensor_over_candidate);
    }
  }
  // The ring's median error decides; with ring_scale_correction the candidate is first scaled by
  // the ring's median sensor/candidate ratio, and the error left after that decides.
  void Judge() {
    accept_.assign(errors_.size(), 0);
    median_.assign(errors_.size(), 1.f);
    scale_.assign(errors_.size(), 1.f);
    for (size_t l = 0; l < errors_.size(); ++l) {
      if (static_cast<int>(errors_[l].size()) < options_.min_ring_samples) continue;
      if (options_.ring_scale_correction) {
        const float scale = Median(ratios_[l]);
        std::vector<float> left;
        for (float r : ratios_[l]) left.push_back(std::abs(r / scale - 1.f));
        median_[l] = Median(left);
        scale_[l] = scale;
        accept_[l] = median_[l] <= options_.max_ring_error &&
                     std::abs(scale - 1.f) <= options_.max_ring_scale;
      } else {
        median_[l] = Median(errors_[l]);
        accept_[l] = median_[l] <= options_.max_ring_error;
      }
    }
  }
  // The verdict that applies at a hole pixel: its piece's, or its hole's.
  size_t At(int x, int y) const {
    const int hole = holes_.labels.at<int>(y, x);
    const size_t piece = Piece(x, y, hole);
    return static_cast<int>(errors_[piece].size()) >= options_.min_ring_samples ? piece : hole;
  }
  bool accepted(size_t v) const { return accept_[v]; }
  float scale(size_t v) const { return scale_[v]; }
  float median(size_t v) const { return median_[v]; }

 private:
  size_t Piece(int x, int y, int label) const {
    return holes_.count + static_cast<size_t>(label) * cells_ +
           static_cast<size_t>(y / cell_) * cells_x_ + x / cell_;
  }
  const Holes& holes_;
  const ValidationOptions& options_;
  int cell_ = 0, cells_x_ = 0;
  size_t cells_ = 0;
  std::vector<std::vector<float>> errors_, ratios_;  // relative errors; sensor / candidate
  std::vector<uint8_t> accept_;
  std::vector<float> median_, scale_;
};

// Fills the hole pixels whose verdict accepts the candidate, that the shadow geometry and the
// third view allow, and that are still empty (and fillable, when given).
void FillAccepted(const cv::Mat& candidate, const RgbdFrame& key1, const RingVerdicts& verdicts,
                  const PhotometricCheck& photometric, const ValidationOptions& options,
                  DepthSource source, const cv::Mat& fillable, DepthFill* fill) {
  const uint8_t shadow = static_cast<uint8_t>(HoleCode::kShadow);
  for (int y = 0; y < candidate.rows; ++y) {
    const uint8_t* hole_row = key1.hole_mask.ptr<uint8_t>(y);
    const float* depth_row = key1.depth.ptr<float>(y);
    float shadow_near = 0, shadow_far = 0;  // the sensor's depths on either side of a shadow run
    for (int x = 0; x < candidate.cols; ++x) {
      if (hole_row[x] == 0) continue;  // measured: never overwritten
      if (hole_row[x] == shadow && (x == 0 || hole_row[x - 1] != shadow)) {
        int end = x;
        while (end < candidate.cols && hole_row[end] == shadow) ++end;
        const float left = x > 0 ? depth_row[x - 1] : 0.f;
        const float right = end < candidate.cols ? depth_row[end] : 0.f;
        shadow_near = std::min(left, right);
        shadow_far = std::max(left, right);
      }
      if (fill->fill_mask.at<uint8_t>(y, x)) continue;  // filled by an earlier candidate
      if (!fillable.empty() && !fillable.at<uint8_t>(y, x)) continue;
      if (!(candidate.at<float>(y, x) > 0)) continue;
      const size_t v = verdicts.At(x, y);
      const float s = candidate.at<float>(y, x) * verdicts.scale(v);
      if (!verdicts.accepted(v)) {
        ++fill->rejected_by_ring;
        continue;
      }
      // A projector shadow is the far surface hidden from the projector by the near one: depth
      // nearer the near side is the near surface spread over the shadow (block matching's
      // foreground fattening, occluded in one view).
      if (hole_row[x] == shadow && shadow_near > 0 &&
          std::abs(s - shadow_near) <= std::abs(s - shadow_far)) {
        ++fill->rejected_by_shadow;
        continue;
      }
      const double agreement = photometric.Agreement(x, y, s);
      if (agreement <= 0) {
        ++fill->rejected_by_photometry;
        continue;
      }
      fill->filled_depth.at<float>(y, x) = s;
      fill->fill_mask.at<uint8_t>(y, x) = 255;
      fill->source.at<uint8_t>(y, x) = static_cast<uint8_t>(source);
      const double ring = verdicts.median(v) / options.max_ring_error;
      fill->confidence.at<float>(y, x) = static_cast<float>(std::exp(-ring * ring) * agreement);
      ++fill->filled_pixels;
    }
  }
}

}  // namespace

bool ValidationOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.Above("min_depth_m", min_depth_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .Above("max_depth_m", max_depth_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .Require(max_depth_m > min_depth_m, "max_depth_m must be more than min_depth_m")
      .In("ring_px", ring_px, 1, kMaxImageSidePx, kLargerThanAnyImage)
      .In("min_ring_samples", min_ring_samples, 1, kMaxImagePixels, kMoreThanAnImagesPixels)
      .In("ring_cell_px", ring_cell_px, 0, kMaxImageSidePx, kLargerThanAnyImage)
      .Above("max_ring_error", max_ring_error, 0, kMaxRelativeDepth, kBeyondAnyDepthRange)
      // The scale is applied when within 1 +- max_ring_scale: from 1 on it could be 0 or negative.
      .In("max_ring_scale", max_ring_scale, 0, 1, "would allow a scale of zero or less")
      .Require(max_ring_scale < 1, "max_ring_scale must be less than 1 (scales stay positive)")
      .Above("max_pair_error", max_pair_error, 0, kMaxRelativeDepth, kBeyondAnyDepthRange)
      .Above("free_space_margin", free_space_margin, 0, kMaxRelativeDepth, kBeyondAnyDepthRange);
  return c.ok();
}

bool PhotometricOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.In("patch_px", patch_px, 3, 99, "is a larger patch than the check compares")
      .Require(patch_px % 2 == 1, "patch_px must be odd")
      .Above("min_ncc", min_ncc, -1, 1, kMoreThanOne)
      .In("min_patch_std", min_patch_std, 0, kMaxGreyLevel, kBeyondGreyLevels)
      .Above("max_mean_difference", max_mean_difference, 0, kMaxGreyLevel, kBeyondGreyLevels)
      .In("occlusion_margin", occlusion_margin, 0, kMaxRelativeDepth, kBeyondAnyDepthRange)
      .Above("corroboration_depth_step", corroboration_depth_step, 0, kMaxRelativeDepth,
             kBeyondAnyDepthRange)
      .In("corroboration_shift_px", corroboration_shift_px, 0, kMaxImageSidePx,
          kLargerThanAnyImage);
  return c.ok();
}

DepthFill SensorOnly(const RgbdFrame& key1) {
  DepthFill f;
  f.filled_depth = key1.depth.clone();
  f.fill_mask = cv::Mat::zeros(key1.depth.size(), CV_8UC1);
  f.hole_pixels = cv::countNonZero(key1.hole_mask);
  f.source = cv::Mat::zeros(key1.depth.size(), CV_8UC1);
  f.source.setTo(static_cast<uint8_t>(DepthSource::kSensor), key1.hole_mask == 0);
  f.confidence = cv::Mat::zeros(key1.depth.size(), CV_32FC1);
  f.confidence.setTo(1.f, key1.hole_mask == 0);
  f.corroborated = cv::Mat::zeros(key1.depth.size(), CV_8UC1);
  return f;
}

Holes FindHoles(const cv::Mat& hole_mask) {
  Holes h;
  cv::distanceTransform(hole_mask == 0, h.distance, h.labels, cv::DIST_L2, 3, cv::DIST_LABEL_CCOMP);
  double max_label = 0;
  cv::minMaxLoc(h.labels, nullptr, &max_label);
  h.count = static_cast<size_t>(max_label) + 1;
  return h;
}

PhotometricCheck::PhotometricCheck(const RgbdFrame& key1, const ThirdView& third,
                                   const Camera& camera, const PhotometricOptions& options)
    : camera_(camera), rays_(camera), options_(options), third_(third) {
  if (third.frame == nullptr || third.frame->color.empty()) return;
  cv::cvtColor(key1.color, gray1_, cv::COLOR_BGR2GRAY);
  cv::cvtColor(third.frame->color, gray3_, cv::COLOR_BGR2GRAY);
  holes1_ = key1.hole_mask;
  key3_from_key1_ = third.key1_from_key3.Inverse();
}

double PhotometricCheck::Agreement(int x, int y, double depth, bool* corroborates) const {
  if (corroborates) *corroborates = false;
  if (!active()) return 1.0;
  const int r = options_.patch_px / 2;
  const Eigen::Vector2d n = rays_.Ray(x, y);
  const Eigen::Vector3d p3 = key3_from_key1_ * Eigen::Vector3d(n.x() * depth, n.y() * depth, depth);
  if (p3.z() <= 0) return 1.0;
  const Eigen::Vector2d q = camera_.ProjectDistorted(p3);
  const int qx = static_cast<int>(std::lround(q.x())), qy = static_cast<int>(std::lround(q.y()));
  if (qx - r < 0 || qy - r < 0 || qx + r >= gray3_.cols || qy + r >= gray3_.rows) return 1.0;
  if (x - r < 0 || y - r < 0 || x + r >= gray1_.cols || y + r >= gray1_.rows) return 1.0;
  const float sensor3 = third_.frame->depth.at<float>(qy, qx);
  if (sensor3 > 0 && sensor3 < p3.z() * (1.0 - options_.occlusion_margin)) return 1.0;
  const bool hole_only = options_.hole_patches && holes1_.at<uint8_t>(y, x) != 0;
  // Integer sums of 8-bit grey levels (a patch of up to 99 x 99 pixels stays below 2^31): exact,
  // and branch-free (a pixel left out weighs 0), so that the rows vectorise.
  int32_t sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0, count = 0;
  for (int dy = -r; dy <= r; ++dy) {
    const uint8_t* holes = holes1_.ptr<uint8_t>(y + dy) + x;
    const uint8_t* a_row = gray1_.ptr<uint8_t>(y + dy) + x;
    const uint8_t* b_row = gray3_.ptr<uint8_t>(qy + dy) + qx;
    for (int dx = -r; dx <= r; ++dx) {
      const int32_t w = hole_only ? (holes[dx] != 0) : 1;
      const int32_t a = w * a_row[dx], b = w * b_row[dx];
      count += w;
      sa += a;
      sb += b;
      saa += a * a;
      sbb += b * b;
      sab += a * b;
    }
  }
  const double ma = static_cast<double>(sa) / count, mb = static_cast<double>(sb) / count;
  const double va = std::max(0.0, static_cast<double>(saa) / count - ma * ma),
               vb = std::max(0.0, static_cast<double>(sbb) / count - mb * mb);
  const double min_var = options_.min_patch_std * options_.min_patch_std;
  if (va < min_var || vb < min_var) {
    const double diff = std::abs(ma - mb);
    return diff <= options_.max_mean_difference ? 1.0 - 0.5 * diff / options_.max_mean_difference
                                                : 0.0;
  }
  const double ncc = (static_cast<double>(sab) / count - ma * mb) / std::sqrt(va * vb);
  if (ncc < options_.min_ncc) return 0.0;
  if (corroborates) {
    // How far a corroboration_depth_step change of the depth moves the point in the third view.
    const double far = depth * (1.0 + options_.corroboration_depth_step);
    const Eigen::Vector3d p3_far = key3_from_key1_ * Eigen::Vector3d(n.x() * far, n.y() * far, far);
    *corroborates = p3_far.z() > 0 && (camera_.ProjectDistorted(p3_far) - q).norm() >=
                                          options_.corroboration_shift_px;
  }
  return ncc;
}

void CorroborateFill(const RgbdFrame& key1, const std::vector<ThirdView>& views,
                     const Camera& camera, const PhotometricOptions& options,
                     const cv::Mat& eligible, DepthFill* fill) {
  if (fill->corroborated.empty()) fill->corroborated = cv::Mat::zeros(key1.depth.size(), CV_8UC1);
  const float step = static_cast<float>(options.corroboration_depth_step);
  auto pending = [&](int x, int y) {  // filled, eligible and not yet corroborated
    return fill->fill_mask.at<uint8_t>(y, x) != 0 && fill->corroborated.at<uint8_t>(y, x) == 0 &&
           (eligible.empty() || eligible.at<uint8_t>(y, x) != 0);
  };
  for (const ThirdView& view : views) {
    if (view.frame == nullptr) continue;
    const PhotometricCheck check(key1, view, camera, options);
    if (!check.active()) continue;
    for (int y = 0; y + 1 < key1.depth.rows; y += 2) {
      for (int x = 0; x + 1 < key1.depth.cols; x += 2) {
        if (!pending(x, y)) continue;
        const float z = fill->filled_depth.at<float>(y, x);
        bool corroborates = false;
        check.Agreement(x, y, z, &corroborates);
        if (!corroborates) continue;
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx)
            if (pending(x + dx, y + dy) &&
                std::abs(fill->filled_depth.at<float>(y + dy, x + dx) - z) <= step * z)
              fill->corroborated.at<uint8_t>(y + dy, x + dx) = 255;
      }
    }
  }
}

namespace {

// Whether `view`'s sensor sees through the point p (view's camera frame): all of the 3x3 pixels
// around its projection measured and farther than it by `margin` (relative).
bool SeesThrough(const cv::Mat& view_depth, const Camera& camera, const Eigen::Vector3d& p,
                 double margin) {
  if (p.z() <= 0) return false;
  const Eigen::Vector2d q = camera.ProjectDistorted(p);
  const int qx = static_cast<int>(std::lround(q.x())), qy = static_cast<int>(std::lround(q.y()));
  if (qx < 1 || qy < 1 || qx + 1 >= view_depth.cols || qy + 1 >= view_depth.rows) return false;
  const float beyond = static_cast<float>(p.z() * (1.0 + margin));
  for (int dy = -1; dy <= 1; ++dy) {
    const float* row = view_depth.ptr<float>(qy + dy);
    for (int dx = -1; dx <= 1; ++dx)
      if (!(row[qx + dx] > beyond)) return false;  // unmeasured (0) or not beyond
  }
  return true;
}

}  // namespace

void RemoveSeenThrough(const RgbdFrame& key1, const std::vector<ThirdView>& views,
                       const Camera& camera, double free_space_margin, DepthFill* fill) {
  const UndistortedPixels rays(camera);
  const float margin = static_cast<float>(free_space_margin);
  auto drop = [&](int x, int y) {
    fill->fill_mask.at<uint8_t>(y, x) = 0;
    fill->filled_depth.at<float>(y, x) = 0.f;
    fill->source.at<uint8_t>(y, x) = static_cast<uint8_t>(DepthSource::kNone);
    fill->confidence.at<float>(y, x) = 0.f;
    --fill->filled_pixels;
    ++fill->rejected_by_free_space;
  };
  for (const ThirdView& view : views) {
    if (view.frame == nullptr || view.frame->depth.type() != CV_32FC1) continue;
    const SE3 view_from_key1 = view.key1_from_key3.Inverse();
    // One filled pixel per 2x2 block is tested (as CorroborateFill does); a seen-through one
    // drops the block's filled pixels within the margin of its depth.
    for (int y = 0; y + 1 < key1.depth.rows; y += 2) {
      for (int x = 0; x + 1 < key1.depth.cols; x += 2) {
        int tx = -1, ty = -1;
        for (int i = 0; i < 4 && tx < 0; ++i)
          if (fill->fill_mask.at<uint8_t>(y + i / 2, x + i % 2) != 0)
            tx = x + i % 2, ty = y + i / 2;
        if (tx < 0) continue;
        const float z = fill->filled_depth.at<float>(ty, tx);
        const Eigen::Vector2d n = rays.Ray(tx, ty);
        if (!SeesThrough(view.frame->depth, camera,
                         view_from_key1 * Eigen::Vector3d(n.x() * z, n.y() * z, z),
                         free_space_margin))
          continue;
        for (int i = 0; i < 4; ++i) {
          const int bx = x + i % 2, by = y + i / 2;
          if (fill->fill_mask.at<uint8_t>(by, bx) != 0 &&
              std::abs(fill->filled_depth.at<float>(by, bx) - z) <= margin * z)
            drop(bx, by);
        }
      }
    }
  }
}

bool ValidateAndFill(const cv::Mat& candidate, const RgbdFrame& key1, const Holes& holes,
                     const PhotometricCheck& photometric, const ValidationOptions& options,
                     DepthSource source, DepthFill* fill, std::vector<float>* errors,
                     std::vector<float>* errors_m, const cv::Mat& fillable) {
  // Against the sensor: over the image, and in a ring around each hole.
  RingVerdicts verdicts(holes, candidate.size(), options);
  std::vector<float> all_errors;
  for (int y = 0; y < candidate.rows; ++y) {
    for (int x = 0; x < candidate.cols; ++x) {
      const float s = candidate.at<float>(y, x), k = key1.depth.at<float>(y, x);
      if (!(s > 0) || !(k > 0)) continue;
      const float e = std::abs(s - k) / k;
      all_errors.push_back(e);
      errors_m->push_back(std::abs(s - k));
      if (holes.distance.at<float>(y, x) <= options.ring_px) verdicts.AddRingSample(x, y, e, k / s);
    }
  }
  errors->insert(errors->end(), all_errors.begin(), all_errors.end());
  if (all_errors.empty() || Median(all_errors) > options.max_pair_error) return false;
  verdicts.Judge();
  FillAccepted(candidate, key1, verdicts, photometric, options, source, fillable, fill);
  return true;
}

}  // namespace gf
