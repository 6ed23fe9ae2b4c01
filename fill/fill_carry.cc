#include "fill/fill_carry.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"

namespace gf {

bool FillCarryOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.In("max_keyframes", max_keyframes, 0, kMaxFramesInMemory, kMoreFramesThanMemory)
      .In("min_agreeing", min_agreeing, 1, kMaxFramesInMemory, kMoreFramesThanMemory)
      .Above("agreement", agreement, 0, 1, kMoreThanOne)
      .Require(agreement < 1, "agreement must be less than 1 (a relative depth difference)");
  return c.ok();
}

KeyframeFillPoints FillPointsInWorld(const StereoFillResult& fill, const SE3& world_from_camera,
                                     const Camera& camera) {
  KeyframeFillPoints points;
  if (!fill.success || fill.fill_mask.empty()) return points;
  const UndistortedPixels rays(camera);
  for (int y = 0; y < fill.fill_mask.rows; ++y)
    for (int x = 0; x < fill.fill_mask.cols; ++x) {
      if (!fill.fill_mask.at<uint8_t>(y, x)) continue;
      const auto source = static_cast<DepthSource>(fill.source.at<uint8_t>(y, x));
      if (source != DepthSource::kStereo && source != DepthSource::kColmap) continue;
      const double z = fill.filled_depth.at<float>(y, x);
      const Eigen::Vector2d n = rays.Ray(x, y);
      points.world_points.push_back(
          (world_from_camera * Eigen::Vector3d(n.x() * z, n.y() * z, z)).cast<float>());
    }
  return points;
}

std::string CarriedFillResult::BriefReport() const {
  std::ostringstream s;
  s << filled_pixels << " filled, " << carried_pixels << " carried from earlier keyframes, "
    << corrected_pixels << " own fills corrected";
  return s.str();
}

namespace {

// The result before carrying: the keyframe's own fill, or its sensor depth alone.
CarriedFillResult StartFromOwnFill(const RgbdFrame& key1, const StereoFillResult* own) {
  CarriedFillResult r;
  if (own != nullptr && own->success) {
    r.filled_depth = own->filled_depth.clone();
    r.fill_mask = own->fill_mask.clone();
    r.source = own->source.clone();
    r.confidence = own->confidence.clone();
    r.corroborated = own->corroborated.empty()
                         ? cv::Mat::zeros(key1.depth.size(), CV_8UC1)
                         : own->corroborated.clone();
  } else {
    r.filled_depth = key1.depth.clone();
    r.fill_mask = cv::Mat::zeros(key1.depth.size(), CV_8UC1);
    r.source = cv::Mat::zeros(key1.depth.size(), CV_8UC1);
    r.source.setTo(static_cast<uint8_t>(DepthSource::kSensor), key1.hole_mask == 0);
    r.confidence = cv::Mat::zeros(key1.depth.size(), CV_32FC1);
    r.confidence.setTo(1.f, key1.hole_mask == 0);
    r.corroborated = cv::Mat::zeros(key1.depth.size(), CV_8UC1);
  }
  r.filled_pixels = cv::countNonZero(r.fill_mask);
  return r;
}

// Each earlier view's fill points projected into key1's hole pixels: candidates[s * n + k] is the
// nearest depth view k leaves on hole pixel s (0: none); `hole_pixels` lists the pixels.
std::vector<float> ProjectIntoHoles(const cv::Mat& hole_mask, const SE3& world_from_key1,
                                    const std::vector<const KeyframeFillPoints*>& views,
                                    const Camera& camera, std::vector<cv::Point>* hole_pixels) {
  // One slot per hole pixel.
  cv::Mat slot(hole_mask.size(), CV_32SC1, cv::Scalar(-1));
  for (int y = 0; y < slot.rows; ++y)
    for (int x = 0; x < slot.cols; ++x)
      if (hole_mask.at<uint8_t>(y, x)) {
        slot.at<int>(y, x) = static_cast<int>(hole_pixels->size());
        hole_pixels->emplace_back(x, y);
      }
  const size_t n = views.size();
  std::vector<float> candidates(hole_pixels->size() * n, 0.f);
  const SE3 key1_from_world = world_from_key1.Inverse();
  const Eigen::Matrix3f rotation = key1_from_world.RotationMatrix().cast<float>();
  const Eigen::Vector3f translation = key1_from_world.translation().cast<float>();
  // Camera::ProjectDistorted in float, inlined: this loop projects every earlier fill point.
  const LensModel<float> lens(camera.distortion);
  const float fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy),
              cx = static_cast<float>(camera.cx) + 0.5f, cy = static_cast<float>(camera.cy) + 0.5f;
  for (size_t k = 0; k < n; ++k) {
    for (const Eigen::Vector3f& world : views[k]->world_points) {
      const Eigen::Vector3f p = rotation * world + translation;
      if (!(p.z() > 0)) continue;
      float x, y;
      lens.Distort(p.x() / p.z(), p.y() / p.z(), &x, &y);
      // + 0.5 in cx, cy: truncating a value >= 0 then rounds to the nearest pixel.
      const float u = fx * x + cx, v = fy * y + cy;
      if (!(u >= 0 && v >= 0 && u < slot.cols && v < slot.rows)) continue;
      const int s = slot.at<int>(static_cast<int>(v), static_cast<int>(u));
      if (s < 0) continue;
      float& c = candidates[s * n + k];
      if (c == 0.f || p.z() < c) c = p.z();
    }
  }
  return candidates;
}

}  // namespace

CarriedFillResult CarryFills(const RgbdFrame& key1, const SE3& world_from_key1,
                             const StereoFillResult* own,
                             const std::vector<const KeyframeFillPoints*>& earlier,
                             const Camera& camera, const FillCarryOptions& options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  GF_CHECK(key1.depth.type() == CV_32FC1 && key1.hole_mask.type() == CV_8UC1 &&
               key1.depth.size() == key1.hole_mask.size(),
           "need metric depth and a hole mask of the same size");
  CarriedFillResult r = StartFromOwnFill(key1, own);
  std::vector<const KeyframeFillPoints*> views;
  for (const KeyframeFillPoints* v : earlier)
    if (v != nullptr && !v->world_points.empty()) views.push_back(v);
  if (options.max_keyframes == 0 || views.empty()) return r;
  if (static_cast<int>(views.size()) > options.max_keyframes)
    views.erase(views.begin(), views.end() - options.max_keyframes);

  std::vector<cv::Point> hole_pixels;
  const std::vector<float> candidates =
      ProjectIntoHoles(key1.hole_mask, world_from_key1, views, camera, &hole_pixels);
  // A hole pixel takes the median of the views' depths when enough of them agree with it.
  const size_t n = views.size();
  std::vector<float> values;
  for (size_t s = 0; s < hole_pixels.size(); ++s) {
    values.clear();
    for (size_t k = 0; k < n; ++k)
      if (candidates[s * n + k] > 0) values.push_back(candidates[s * n + k]);
    if (static_cast<int>(values.size()) < options.min_agreeing) continue;
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    const float median = values[values.size() / 2];
    const float tolerance = static_cast<float>(options.agreement) * median;
    int agreeing = 0;
    for (float v : values) agreeing += std::abs(v - median) <= tolerance;
    if (agreeing < options.min_agreeing) continue;
    const cv::Point q = hole_pixels[s];
    float& depth = r.filled_depth.at<float>(q);
    if (r.fill_mask.at<uint8_t>(q)) {
      if (!options.correct_own_fills || std::abs(depth - median) <= tolerance) continue;
      ++r.corrected_pixels;
    } else {
      ++r.carried_pixels;
      ++r.filled_pixels;
    }
    depth = median;
    r.fill_mask.at<uint8_t>(q) = 255;
    r.source.at<uint8_t>(q) = static_cast<uint8_t>(DepthSource::kCarried);
    r.confidence.at<float>(q) = static_cast<float>(agreeing) / static_cast<float>(values.size());
    r.corroborated.at<uint8_t>(q) = 0;
  }
  return r;
}

FillCarrier::FillCarrier(const Camera& camera, const FillCarryOptions& options)
    : camera_(camera), options_(options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
}

CarriedFillResult FillCarrier::Next(const RgbdFrame& key1, const SE3& world_from_key1,
                                    const StereoFillResult* own) {
  std::vector<const KeyframeFillPoints*> earlier;
  for (const KeyframeFillPoints& e : earlier_) earlier.push_back(&e);
  CarriedFillResult c = CarryFills(key1, world_from_key1, own, earlier, camera_, options_);
  if (options_.max_keyframes > 0) {
    // Own fills only, never the carried ones, so that an error cannot feed on itself.
    earlier_.push_back(own ? FillPointsInWorld(*own, world_from_key1, camera_)
                           : KeyframeFillPoints{});
    while (static_cast<int>(earlier_.size()) > options_.max_keyframes) earlier_.pop_front();
  }
  return c;
}

}  // namespace gf
