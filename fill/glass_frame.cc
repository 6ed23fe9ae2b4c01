#include "fill/glass_frame.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <opencv2/imgproc.hpp>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"
#include "acquisition/plane_fit.h"
#include "acquisition/stats.h"

namespace gf {
namespace {

// The ray (x/z, y/z, 1) through every pixel, CV_32FC3.
cv::Mat PixelRays(const Camera& camera) {
  const UndistortedPixels pixels(camera);
  cv::Mat rays(camera.height, camera.width, CV_32FC3);
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const Eigen::Vector2d r = pixels.Ray(x, y);
      rays.at<cv::Vec3f>(y, x) = cv::Vec3f(static_cast<float>(r.x()), static_cast<float>(r.y()), 1);
    }
  return rays;
}

Eigen::Vector3d PointAt(const cv::Mat& rays, const cv::Mat& depth_m, int x, int y) {
  const cv::Vec3f& r = rays.at<cv::Vec3f>(y, x);
  const double z = depth_m.at<float>(y, x);
  return Eigen::Vector3d(r[0] * z, r[1] * z, z);
}

// A plane in the camera frame, its normal towards the camera (normal . p + offset = 0, offset > 0).
using Plane = FittedPlane;

// A plane through points: the one with the most within plane_inlier_m (RANSAC, a fixed seed),
// refined by least squares over those. False when none has 3.
bool FitPlane(const std::vector<Eigen::Vector3d>& points, const GlassFrameOptions& o,
              Plane* plane) {
  return RansacPlane(points, o.plane_inlier_m, o.plane_iterations, plane);
}

// The points of every step-th pixel with a reading inside `area` (and not in `except`, if given).
std::vector<Eigen::Vector3d> PointsIn(const cv::Mat& rays, const cv::Mat& depth_m,
                                      const cv::Rect& area, int step, const cv::Mat& except) {
  std::vector<Eigen::Vector3d> points;
  for (int y = area.y; y < area.y + area.height; y += step)
    for (int x = area.x; x < area.x + area.width; x += step)
      if (depth_m.at<float>(y, x) > 0 && (except.empty() || !except.at<uint8_t>(y, x)))
        points.push_back(PointAt(rays, depth_m, x, y));
  return points;
}

// Hole runs along each row that lie between two depths far apart (a shadow), or touch the image's
// side: 255.
cv::Mat ShadowRuns(const cv::Mat& depth_m, double relative_jump) {
  cv::Mat shadow(depth_m.size(), CV_8U, cv::Scalar(0));
  for (int y = 0; y < depth_m.rows; ++y) {
    const float* row = depth_m.ptr<float>(y);
    for (int x = 0; x < depth_m.cols;) {
      if (row[x] > 0) {
        ++x;
        continue;
      }
      const int start = x;
      while (x < depth_m.cols && !(row[x] > 0)) ++x;
      const float left = start > 0 ? row[start - 1] : 0.f, right = x < depth_m.cols ? row[x] : 0.f;
      const bool open = left <= 0 || right <= 0;
      if (open || std::abs(left - right) > relative_jump * std::min(left, right))
        shadow.row(y).colRange(start, x).setTo(255);
    }
  }
  return shadow;
}

// The support's extent in the image: its inliers closed over objects (15 cm), the largest piece,
// with everything it encloses.
cv::Mat SupportExtent(const cv::Mat& on_plane, double pixels_per_m) {
  const int k = std::max(3, static_cast<int>(0.15 * pixels_per_m) | 1);
  cv::Mat closed;
  cv::morphologyEx(on_plane, closed, cv::MORPH_CLOSE,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(closed, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  cv::Mat extent(on_plane.size(), CV_8U, cv::Scalar(0));
  if (contours.empty()) return extent;
  size_t largest = 0;
  for (size_t i = 1; i < contours.size(); ++i)
    if (cv::contourArea(contours[i]) > cv::contourArea(contours[largest])) largest = i;
  cv::drawContours(extent, contours, static_cast<int>(largest), cv::Scalar(255), cv::FILLED);
  return extent;
}

// Up to `count` planes, largest first, each fitted to the points the ones before left, while a
// plane holds at least a twentieth of all the points.
std::vector<Plane> SupportPlanes(std::vector<Eigen::Vector3d> points, int count,
                                 const GlassFrameOptions& o) {
  const double twentieth = static_cast<double>(points.size()) / 20;
  return RansacPlanes(std::move(points), o.plane_inlier_m, o.plane_iterations, count, twentieth);
}

// Step 2: the glass regions (255) from the holes over the supports that are not shadows.
cv::Mat FindGlassRegions(const cv::Mat& depth_m, const cv::Mat& rays,
                         const std::vector<Plane>& planes, const GlassFrameOptions& o,
                         double pixels_per_m) {
  cv::Mat extent(depth_m.size(), CV_8U, cv::Scalar(0));
  for (const Plane& plane : planes) {
    cv::Mat on_plane(depth_m.size(), CV_8U, cv::Scalar(0));
    for (int y = 0; y < depth_m.rows; ++y)
      for (int x = 0; x < depth_m.cols; ++x)
        if (depth_m.at<float>(y, x) > 0 && std::abs(plane.normal.dot(PointAt(rays, depth_m, x, y)) +
                                                    plane.offset) < o.plane_inlier_m)
          on_plane.at<uint8_t>(y, x) = 255;
    extent |= SupportExtent(on_plane, pixels_per_m);
  }
  cv::Mat evidence = (depth_m <= 0) & extent & ~ShadowRuns(depth_m, o.shadow_relative_jump);
  const int k = std::max(3, static_cast<int>(o.close_m * pixels_per_m) | 1);
  cv::morphologyEx(evidence, evidence, cv::MORPH_CLOSE,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(evidence, labels, stats, centroids, 8, CV_32S);
  const double min_pixels = o.min_region_m2 * pixels_per_m * pixels_per_m;
  cv::Mat mask(depth_m.size(), CV_8U, cv::Scalar(0));
  for (int label = 1; label < n; ++label) {
    if (stats.at<int>(label, cv::CC_STAT_AREA) < min_pixels) continue;
    std::vector<cv::Point> points;
    cv::findNonZero(labels == label, points);
    std::vector<cv::Point> hull;
    cv::convexHull(points, hull);
    cv::fillConvexPoly(mask, hull, cv::Scalar(255));
  }
  return mask;
}

// A region's pixels with their rays.
struct RegionPixel {
  int x, y;
  Eigen::Vector3d ray;  // (x/z, y/z, 1)
};

// Where the ray s * r passes the axis (base + u * axis) nearest: the height u there and the
// distance between them.
void NearestToAxis(const Eigen::Vector3d& r, const Eigen::Vector3d& base,
                   const Eigen::Vector3d& axis, double* u, double* distance) {
  const double ra = r.dot(axis), rr = r.dot(r), rb = r.dot(base), ba = base.dot(axis);
  const double den = rr - ra * ra;
  const double s = den > 1e-12 ? (rb - ra * ba) / den : 0.0;
  *u = s * ra - ba;
  *distance = (s * r - base - *u * axis).norm();
}

// Nearest-the-camera solution s of |(s r - base) - ((s r - base) . axis) axis| = radius.
bool FrontOfCylinder(const Eigen::Vector3d& r, const Eigen::Vector3d& base,
                     const Eigen::Vector3d& axis, double radius, double* s) {
  const Eigen::Vector3d w = r - r.dot(axis) * axis, v = -(base - base.dot(axis) * axis);
  const double a = w.dot(w), b = 2 * w.dot(v), c = v.dot(v) - radius * radius;
  const double disc = b * b - 4 * a * c;
  if (a <= 0 || disc < 0) return false;
  *s = (-b - std::sqrt(disc)) / (2 * a);
  return *s > 0;
}

// Step 3: the radius per height step (keyed by step, from -3 below the base) of a standing object
// whose base front is `front`, axis along `axis`, from its silhouette: the first and last pixel
// of each row, whose rays graze the surface where they pass the axis nearest, at the radius.
// Its base radius (the median of the three lowest steps') in *radius.
std::map<int, double> Profile(const std::vector<RegionPixel>& region, const Eigen::Vector3d& front,
                              const Eigen::Vector3d& away, const Eigen::Vector3d& axis,
                              const GlassFrameOptions& o, double* radius) {
  std::map<int, std::pair<int, int>> row_ends;  // row -> (index of first, of last) pixel
  for (int i = 0; i < static_cast<int>(region.size()); ++i) {
    auto [it, added] = row_ends.try_emplace(region[i].y, i, i);
    if (region[i].x < region[it->second.first].x) it->second.first = i;
    if (region[i].x > region[it->second.second].x) it->second.second = i;
  }
  std::map<int, double> profile;
  *radius = 0.02;
  for (int it = 0; it < 4; ++it) {
    const Eigen::Vector3d base = front + *radius * away;
    std::map<int, std::vector<double>> by_step;
    for (const auto& [row, ends] : row_ends)
      for (int i : {ends.first, ends.second}) {
        double u, distance;
        NearestToAxis(region[i].ray, base, axis, &u, &distance);
        const int step = static_cast<int>(std::floor(u / o.height_step_m));
        if (step >= -3) by_step[step].push_back(distance);
      }
    profile.clear();
    for (auto& [step, distances] : by_step)
      if (distances.size() >= 2) profile[step] = Median(distances);
    std::vector<double> lowest;
    for (const auto& [step, r] : profile)
      if (step >= 0 && lowest.size() < 3) lowest.push_back(r);
    if (lowest.empty()) return {};
    *radius = Median(lowest);
  }
  return profile;
}

// Steps 3 and 4 for one region: fits the standing surface of revolution and puts its depth in
// depth_filled where the sensor read nothing or read through it.
void ShapeRegion(const std::vector<RegionPixel>& region, const Plane& support,
                 const cv::Mat& depth_m, const GlassFrameOptions& o, cv::Mat* depth_filled,
                 GlassFrameRegion* out) {
  const Eigen::Vector3d& axis = support.normal;
  // Depth (z) at which a ray (x/z, y/z, 1) meets the support; 0 where it does not, in front.
  auto support_depth = [&support](const Eigen::Vector3d& ray) {
    const double along = support.normal.dot(ray);
    return along < -1e-6 ? -support.offset / along : 0.0;
  };
  // The base's front: where the region's nearest ray (in its lowest percent) meets the plane.
  std::vector<std::pair<double, Eigen::Vector3d>> hits;
  for (const RegionPixel& p : region) {
    const double t = support_depth(p.ray);
    if (t > 0) hits.emplace_back(t * p.ray.norm(), t * p.ray);
  }
  if (hits.empty()) return;
  const size_t k = hits.size() / 100;
  std::nth_element(hits.begin(), hits.begin() + k, hits.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  const Eigen::Vector3d front = hits[k].second;
  Eigen::Vector3d away = front.normalized() - front.normalized().dot(axis) * axis;
  if (away.norm() < 1e-6) return;  // looking straight down the axis
  away.normalize();
  double radius = 0;
  const std::map<int, double> profile = Profile(region, front, away, axis, o, &radius);
  if (profile.empty() || radius < o.min_radius_m || radius > o.max_radius_m) return;
  out->radius_m = static_cast<float>(radius);
  if ((profile.rbegin()->first + 1) * o.height_step_m < o.min_height_m) return;
  out->shaped = true;
  const Eigen::Vector3d base = front + radius * away;
  for (const RegionPixel& p : region) {
    // The radius at the height where the ray passes the axis nearest (where a silhouette ray
    // grazes the surface: the heights the profile was measured at).
    double u, distance, z = 0;
    NearestToAxis(p.ray, base, axis, &u, &distance);
    const auto step = profile.find(static_cast<int>(std::floor(u / o.height_step_m)));
    if (step == profile.end() || !FrontOfCylinder(p.ray, base, axis, step->second, &z)) continue;
    out->height_m = std::max(out->height_m, static_cast<float>((z * p.ray - base).dot(axis)));
    // A reading is replaced only where it reads the support through the glass: on the plane (or
    // beyond it) and behind the surface. A reading above the support may be the glass itself (a
    // lid, a rim) or something behind it; one frame does not tell which, so it stays.
    const float sensor = depth_m.at<float>(p.y, p.x);
    const double support_z = support_depth(p.ray);
    if (sensor > 0 && (sensor <= z + o.behind_margin_m || support_z <= 0 ||
                       sensor < support_z - o.plane_inlier_m))
      continue;
    depth_filled->at<float>(p.y, p.x) = static_cast<float>(z);
    ++out->replaced;
  }
}

// The surface a region stands on: the plane read around it (a window half its size wider on
// each side and half its height lower), or the frame's support plane when too little is read
// there.
Plane RegionSupport(const std::vector<RegionPixel>& region, const cv::Mat& rays,
                    const cv::Mat& depth_m, const cv::Mat& glass_mask, const Plane& frame_plane,
                    const GlassFrameOptions& o) {
  cv::Rect box(region.front().x, region.front().y, 1, 1);
  for (const RegionPixel& p : region) box |= cv::Rect(p.x, p.y, 1, 1);
  const cv::Rect window =
      cv::Rect(box.x - box.width / 2, box.y, 2 * box.width, box.height + box.height / 2) &
      cv::Rect(0, 0, depth_m.cols, depth_m.rows);
  const int step = std::max(1, static_cast<int>(std::sqrt(window.area() / 4000.0)));
  const std::vector<Eigen::Vector3d> points = PointsIn(rays, depth_m, window, step, glass_mask);
  Plane local;
  constexpr int kMinPoints = 50;
  if (static_cast<int>(points.size()) < kMinPoints || !FitPlane(points, o, &local) ||
      local.inliers < kMinPoints)
    return frame_plane;
  return local;
}

}  // namespace

bool GlassFrameOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.Above("plane_inlier_m", plane_inlier_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .In("plane_iterations", plane_iterations, 1, kMaxIterations * 100,
          "is more draws than useful")
      .In("support_planes", support_planes, 1, 100, "is more planes than a frame holds")
      .In("plane_sample_step_px", plane_sample_step_px, 1, kMaxImageSidePx, kLargerThanAnyImage)
      .Above("shadow_relative_jump", shadow_relative_jump, 0, kMaxRelativeDepth,
             "is more than any depth ratio")
      .In("close_m", close_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("min_region_m2", min_region_m2, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("height_step_m", height_step_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("min_radius_m", min_radius_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("max_radius_m", max_radius_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Require(min_radius_m <= max_radius_m, "min_radius_m is more than max_radius_m")
      .In("min_height_m", min_height_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .In("behind_margin_m", behind_margin_m, 0, kMaxDepthM, kFartherThanAnySensor);
  return c.ok();
}

std::string GlassFrameResult::BriefReport() const {
  int shaped = 0;
  for (const GlassFrameRegion& r : regions) shaped += r.shaped;
  char buffer[200];
  std::snprintf(buffer, sizeof(buffer),
                "%s; %d glass regions (%d shaped), %d glass pixels, %d pixels given the glass's "
                "depth",
                plane_found ? "support plane found" : "no support plane",
                static_cast<int>(regions.size()), shaped,
                glass_mask.empty() ? 0 : cv::countNonZero(glass_mask), replaced_pixels);
  return buffer;
}

cv::Mat GlassRegionsFromBoxes(const cv::Mat& color, const std::vector<cv::Rect>& boxes,
                              int iterations) {
  GF_CHECK(color.type() == CV_8UC3, "GrabCut needs a CV_8UC3 colour image");
  GF_CHECK(iterations > 0, "GrabCut needs at least one iteration");
  cv::Mat regions(color.size(), CV_32S, cv::Scalar(0));
  const cv::Rect image(0, 0, color.cols, color.rows);
  for (size_t k = 0; k < boxes.size(); ++k) {
    const cv::Rect box = boxes[k] & image;
    if (box.width < 2 || box.height < 2) continue;
    // GrabCut starts its colour models from k-means on OpenCV's per-thread generator: seeded here
    // (and given back), so that a box gives the same mask whatever ran before.
    const uint64 state = cv::theRNG().state;
    cv::theRNG().state = 0x9E3779B97F4A7C15ull;
    // On the box and a quarter of its size round it (the background's colours near the object;
    // the whole image only costs time).
    const cv::Rect around = cv::Rect(box.x - box.width / 4, box.y - box.height / 4,
                                     box.width * 3 / 2, box.height * 3 / 2) &
                            image;
    cv::Mat labels, background, foreground;
    cv::grabCut(color(around), labels, box - around.tl(), background, foreground, iterations,
                cv::GC_INIT_WITH_RECT);
    cv::theRNG().state = state;
    regions(around).setTo(static_cast<int>(k + 1),
                          (labels == cv::GC_FGD) | (labels == cv::GC_PR_FGD));
  }
  return regions;
}

GlassFrameResult FindGlassInFrame(const cv::Mat& color, const cv::Mat& depth_m,
                                  const Camera& camera, const GlassFrameOptions& options,
                                  const cv::Mat& given) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  GF_CHECK(
      depth_m.type() == CV_32FC1 && depth_m.cols == camera.width && depth_m.rows == camera.height,
      "depth must be CV_32F metres at the camera's size");
  GF_CHECK(given.empty() || ((given.type() == CV_8UC1 || given.type() == CV_32SC1) &&
                             given.size() == depth_m.size()),
           "the given glass must be CV_8U or CV_32S at the depth's size");
  GF_CHECK(color.empty() || color.size() == depth_m.size(), "colour and depth differ in size");
  GlassFrameResult result;
  result.depth_filled = depth_m.clone();
  result.glass_mask = cv::Mat::zeros(depth_m.size(), CV_8U);
  const cv::Mat rays = PixelRays(camera);
  const std::vector<Plane> planes =
      SupportPlanes(PointsIn(rays, depth_m, cv::Rect(0, 0, depth_m.cols, depth_m.rows),
                             options.plane_sample_step_px, cv::Mat()),
                    options.support_planes, options);
  result.plane_found = !planes.empty();
  const Plane plane = result.plane_found ? planes.front() : Plane();
  result.plane_normal = plane.normal, result.plane_offset_m = plane.offset;
  result.plane_inliers = plane.inliers;
  if (!result.plane_found && given.empty()) return result;
  // Pixels per metre at the frame's typical depth (the median reading).
  std::vector<float> depths;
  for (int y = 0; y < depth_m.rows; y += 8)
    for (int x = 0; x < depth_m.cols; x += 8)
      if (depth_m.at<float>(y, x) > 0) depths.push_back(depth_m.at<float>(y, x));
  const double pixels_per_m = 0.5 * (camera.fx + camera.fy) / Median(depths, 1.f);
  result.glass_mask = !given.empty()
                          ? cv::Mat(given != 0)
                          : FindGlassRegions(depth_m, rays, planes, options, pixels_per_m);
  cv::Mat labels;
  int n = 0;
  if (given.type() == CV_32SC1) {
    labels = cv::max(given, 0);
    double most = 0;
    cv::minMaxLoc(labels, nullptr, &most);
    n = static_cast<int>(most) + 1;
  } else {
    n = cv::connectedComponents(result.glass_mask, labels, 8, CV_32S);
  }
  std::vector<std::vector<RegionPixel>> regions(std::max(0, n - 1));
  for (int y = 0; y < labels.rows; ++y)
    for (int x = 0; x < labels.cols; ++x)
      if (const int label = labels.at<int>(y, x); label > 0) {
        const cv::Vec3f& r = rays.at<cv::Vec3f>(y, x);
        regions[label - 1].push_back({x, y, Eigen::Vector3d(r[0], r[1], r[2])});
      }
  for (const std::vector<RegionPixel>& region : regions) {
    if (region.empty()) continue;  // a label given with no pixels
    GlassFrameRegion out;
    out.pixels = static_cast<int>(region.size());
    const Plane support = RegionSupport(region, rays, depth_m, result.glass_mask, plane, options);
    if (support.inliers > 0)
      ShapeRegion(region, support, depth_m, options, &result.depth_filled, &out);
    result.replaced_pixels += out.replaced;
    result.regions.push_back(out);
  }
  return result;
}

}  // namespace gf
