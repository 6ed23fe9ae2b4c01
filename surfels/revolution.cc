#include "surfels/revolution.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>

#include "acquisition/bounds.h"
#include "acquisition/plane_fit.h"
#include "acquisition/stats.h"
#include "surfels/revolution_circles.h"
#include "surfels/surfel_grid.h"

namespace gf {
namespace {

constexpr double kTwoPi = 2 * M_PI;
using revolution_detail::AxisPoint;
using revolution_detail::FitCircles;
using revolution_detail::MeasureFit;

bool IsTransparent(const Surfel& s) {
  return s.source == static_cast<uint8_t>(DepthSource::kTransparent);
}

// Groups the transparent surfels of `map` into objects: surfels within `gap` of one another.
// Groups come out in the order of their first surfel in the map, each in map order
// (deterministic).
std::vector<std::vector<int>> GroupTransparent(const std::vector<Surfel>& map, double gap) {
  const SurfelGrid grid(map, gap, IsTransparent);
  std::vector<bool> seen(map.size(), false);
  std::vector<std::vector<int>> groups;
  for (int start : grid.members()) {
    if (seen[start]) continue;
    std::vector<int> group{start};
    seen[start] = true;
    grid.Walk(&group, &seen, [](int) { return true; });
    groups.push_back(std::move(group));
  }
  return groups;
}

// The direction the normals are most nearly all perpendicular to, or none (false) when they do
// not lie near one plane.
bool AxisOfNormals(const std::vector<Surfel>& map, const std::vector<int>& group, double max_spread,
                   Eigen::Vector3f* axis) {
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (int i : group) {
    const Eigen::Vector3d n = map[i].normal.cast<double>();
    scatter += n * n.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  const Eigen::Vector3d values = eig.eigenvalues();  // ascending
  if (!(values(1) > 0) || values(0) > max_spread * values(1)) return false;
  Eigen::Vector3d a = eig.eigenvectors().col(0).normalized();
  // A sign that does not depend on the solver: the largest component positive.
  int largest = 0;
  a.cwiseAbs().maxCoeff(&largest);
  if (a(largest) < 0) a = -a;
  *axis = a.cast<float>();
  return true;
}

// Rings of surfels every spacing_m up the shape, each ring's surfels spacing_m apart.
void LaySurfels(const RevolutionShape& shape, const Eigen::Vector3f& u, const Eigen::Vector3f& w,
                const Surfel& like, double step_m, double spacing_m, std::vector<Surfel>* out) {
  const int rings = std::max(1, static_cast<int>(std::ceil(shape.height_m / spacing_m)) + 1);
  for (int k = 0; k < rings; ++k) {
    const double h = std::min<double>(shape.height_m, k * spacing_m);
    const int s =
        std::min(static_cast<int>(shape.radius_m.size()) - 1, static_cast<int>(h / step_m));
    const double r = shape.radius_m[s];
    const int around = std::max(8, static_cast<int>(std::ceil(kTwoPi * r / spacing_m)));
    for (int j = 0; j < around; ++j) {
      const double t = kTwoPi * j / around;
      const Eigen::Vector3f radial =
          static_cast<float>(std::cos(t)) * u + static_cast<float>(std::sin(t)) * w;
      Surfel s2 = like;
      s2.position =
          shape.base + static_cast<float>(h) * shape.axis + static_cast<float>(r) * radial;
      s2.normal = radial;
      out->push_back(s2);
    }
  }
}

// Two unit directions perpendicular to `axis` and to each other.
void AcrossAxis(const Eigen::Vector3f& axis, Eigen::Vector3f* u, Eigen::Vector3f* w) {
  const Eigen::Vector3f any =
      std::abs(axis.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY();
  *u = axis.cross(any).normalized();
  *w = axis.cross(*u);
}

// The median distance of the group's surfels from the plane through `mean` (their centroid) that
// fits them best.
double PlaneResidual(const std::vector<Surfel>& map, const std::vector<int>& group,
                     const Eigen::Vector3d& mean) {
  std::vector<Eigen::Vector3d> points;
  for (int i : group) points.push_back(map[i].position.cast<double>());
  const Eigen::Vector3d normal = LeastSquaresNormal(points, mean);
  std::vector<double> off;
  for (const Eigen::Vector3d& p : points) off.push_back(std::abs(normal.dot(p - mean)));
  return Median(off);
}

// The plane an object stands on (world frame): normal . x + offset is the height above it, the
// normal pointing up to the object.
struct Support {
  bool found = false;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset = 0;
  double Height(const Eigen::Vector3f& p) const { return normal.dot(p.cast<double>()) + offset; }
};

// RANSAC draws per support plane, and the most surfels near an object it looks at (every k-th):
// a plane that holds a third of them is drawn with 99.9% certainty (1 - (1 - 1/27)^200); one that
// holds only min_support_share may be missed. The RANSAC's cost does not grow with the map.
constexpr int kSupportIterations = 200;
constexpr size_t kMaxSupportPoints = 4000;
constexpr int kSupportPlanes = 3;

Eigen::Vector3d Centre(const std::vector<Surfel>& map, const std::vector<int>& group) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int i : group) c += map[i].position.cast<double>();
  return c / static_cast<double>(group.size());
}

// The largest planes of the opaque surfels near the group that it may stand on: it lies above
// each (its lowest surfel no more than support_inlier_m under it), its normals a median of at
// least min_support_angle_deg from the plane's (a glass's side is upright on its table; a pane's
// normals are its wall's). The one its normals are most nearly perpendicular to first.
std::vector<Support> CandidateSupports(const std::vector<Surfel>& map,
                                       const std::vector<int>& group,
                                       const std::vector<Eigen::Vector3d>& opaque,
                                       const RevolutionOptions& o) {
  const Eigen::Vector3d centre = Centre(map, group);
  const double reach2 = o.support_radius_m * o.support_radius_m;
  std::vector<Eigen::Vector3d> near;
  for (const Eigen::Vector3d& p : opaque)
    if ((p - centre).squaredNorm() <= reach2) near.push_back(p);
  const size_t stride = near.size() / kMaxSupportPoints + 1;
  std::vector<Eigen::Vector3d> points;
  for (size_t i = 0; i < near.size(); i += stride) points.push_back(near[i]);
  const double min_inliers =
      std::max(3.0, o.min_support_share * static_cast<double>(points.size()));
  const double max_cos = std::cos(o.min_support_angle_deg * M_PI / 180.0);
  std::vector<std::pair<double, Support>> found;  // (median cosine, plane)
  for (const FittedPlane& plane : RansacPlanes(std::move(points), o.support_inlier_m,
                                               kSupportIterations, kSupportPlanes, min_inliers)) {
    Support s{true, plane.normal, plane.offset};
    if (s.normal.dot(centre) + s.offset < 0) s.normal = -s.normal, s.offset = -s.offset;
    double lowest = 1e30;
    std::vector<double> cosines;
    for (int i : group) {
      lowest = std::min(lowest, s.Height(map[i].position));
      cosines.push_back(std::abs(s.normal.dot(map[i].normal.cast<double>())));
    }
    const double cosine = Median(std::move(cosines));
    if (lowest >= -o.support_inlier_m && cosine <= max_cos) found.emplace_back(cosine, s);
  }
  std::stable_sort(found.begin(), found.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Support> supports;
  for (const auto& f : found) supports.push_back(f.second);
  return supports;
}

// The surfels of any source on the surface of a standing object: reached from its transparent
// surfels over gaps of at most cluster_gap_m, above its support (more than twice
// support_inlier_m: not the table), their footprint within max_radius_m of its transparent
// surfels' centre. The sensor's readings of the glass that stayed opaque, and a bottle's label,
// lie on the same surface as the few transparent surfels.
std::vector<int> WholeSurface(const std::vector<Surfel>& map, const SurfelGrid& all,
                              const std::vector<int>& group, const Support& support,
                              const RevolutionOptions& o, std::vector<bool>* seen) {
  Eigen::Vector3d centre = Centre(map, group);
  centre -= (support.normal.dot(centre) + support.offset) * support.normal;
  const double reach2 = o.max_radius_m * o.max_radius_m;
  std::vector<int> surface = group;
  for (int i : group) (*seen)[i] = true;
  all.Walk(&surface, seen, [&](int j) {
    const Eigen::Vector3d p = map[j].position.cast<double>();
    const double h = support.normal.dot(p) + support.offset;
    return h > 2 * o.support_inlier_m && (p - h * support.normal - centre).squaredNorm() <= reach2;
  });
  return surface;
}

// What the surfels laid on an object look like: the glass's median confidence and mean colour.
Surfel LikeGlass(const std::vector<Surfel>& map, const std::vector<int>& glass,
                 const RevolutionOptions& o) {
  std::vector<float> confidence;
  Eigen::Vector3d colour = Eigen::Vector3d::Zero();
  for (int i : glass) {
    confidence.push_back(map[i].confidence);
    colour += Eigen::Vector3d(map[i].red, map[i].green, map[i].blue);
  }
  colour /= glass.size();
  Surfel like;
  like.confidence = Median(std::move(confidence));
  like.radius = static_cast<float>(0.75 * o.spacing_m);
  like.red = static_cast<uint8_t>(colour.x() + 0.5);
  like.green = static_cast<uint8_t>(colour.y() + 0.5);
  like.blue = static_cast<uint8_t>(colour.z() + 0.5);
  like.source = static_cast<uint8_t>(DepthSource::kTransparent);
  like.last_frame = map[glass.back()].last_frame;
  return like;
}

// Standing on a support, its axis is the support's normal and it reaches down to the support.
// `group`: the surfels fitted; `glass`: its transparent ones, whose look the laid surfels take.
bool FitObject(const std::vector<Surfel>& map, const std::vector<int>& group,
               const std::vector<int>& glass, const Support& support, const RevolutionOptions& o,
               RevolutionShape* shape, std::vector<Surfel>* out) {
  Eigen::Vector3f axis = support.normal.cast<float>();
  if (!support.found && !AxisOfNormals(map, group, o.max_axis_spread, &axis)) return false;
  Eigen::Vector3f u, w;
  AcrossAxis(axis, &u, &w);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  double low = 1e30, high = -1e30;
  for (int i : group) {
    mean += map[i].position.cast<double>();
    const double h = axis.dot(map[i].position);
    low = std::min(low, h), high = std::max(high, h);
  }
  mean /= group.size();
  if (support.found) low = -support.offset;  // axis . x on the support
  const Eigen::Vector3f origin = mean.cast<float>();
  const double origin_h = axis.dot(origin);
  std::vector<AxisPoint> points;
  for (int i : group) {
    const Eigen::Vector3f d = map[i].position - origin;
    // A standing object's surfels may lie up to support_inlier_m under its support: at its foot.
    const double h = std::max(0.0, axis.dot(map[i].position) - low);
    points.push_back({u.dot(d), w.dot(d), h, u.dot(map[i].normal), w.dot(map[i].normal)});
  }
  const int steps = std::max(1, static_cast<int>(std::ceil((high - low) / o.height_step_m)));
  Eigen::Vector2d centre;
  std::vector<double> radius;
  if (!FitCircles(points, steps, o.height_step_m, &centre, &radius)) return false;
  for (double r : radius)
    if (r < o.min_radius_m || r > o.max_radius_m) return false;
  MeasureFit(points, centre, radius, o.height_step_m, shape);
  shape->plane_residual_m = static_cast<float>(PlaneResidual(map, group, mean));
  if (shape->residual_m > o.max_residual_m || shape->normal_deg > o.max_normal_angle_deg ||
      shape->residual_m > o.max_residual_share * shape->plane_residual_m ||
      shape->arc_deg < o.min_arc_deg)
    return false;
  shape->axis = axis;
  shape->standing = support.found;
  shape->base = origin + static_cast<float>(centre.x()) * u + static_cast<float>(centre.y()) * w +
                static_cast<float>(low - origin_h) * axis;
  shape->height_m = static_cast<float>(high - low);
  shape->radius_m.assign(radius.begin(), radius.end());
  shape->surfels = static_cast<int>(group.size());
  LaySurfels(*shape, u, w, LikeGlass(map, glass, o), o.height_step_m, o.spacing_m, out);
  return true;
}

// A standing object FitObject refused, for the outline search: its frame on the support under
// the middle of its surface (the glass and what the sensor read of it as opaque), the surface's
// mean normal across the axis, its half width across that normal (5th to 95th percentile), its
// height, and the map's opaque surfels that a hypothesis could hold (not its own). *span: the
// share of its height (support to top) that its surface covers.
StandingObject Standing(const std::vector<Surfel>& map, const std::vector<int>& fitted,
                        const Support& support, const RevolutionOptions& o, double* span) {
  StandingObject s;
  Eigen::Vector3f u, w;
  AcrossAxis(support.normal.cast<float>(), &u, &w);
  s.axis = support.normal, s.u = u.cast<double>(), s.w = w.cast<double>();
  const Eigen::Vector3d mean = Centre(map, fitted);
  s.origin = mean - (support.normal.dot(mean) + support.offset) * support.normal;
  double low = 1e30;
  for (int i : fitted) {
    const double h = s.axis.dot(map[i].position.cast<double>() - s.origin);
    s.height_m = std::max(s.height_m, h);
    low = std::min(low, h);
  }
  *span = s.height_m > 0 ? (s.height_m - low) / s.height_m : 0;
  Eigen::Vector2d outward = Eigen::Vector2d::Zero();
  for (int i : fitted) {
    const Eigen::Vector3d n = map[i].normal.cast<double>();
    outward += Eigen::Vector2d(s.u.dot(n), s.w.dot(n));
  }
  if (outward.norm() > 1e-9) s.outward = outward.normalized();
  const Eigen::Vector2d side(-s.outward.y(), s.outward.x());
  std::vector<double> lateral;
  for (int i : fitted) {
    const Eigen::Vector3d rel = map[i].position.cast<double>() - s.origin;
    lateral.push_back(side.dot(Eigen::Vector2d(s.u.dot(rel), s.w.dot(rel))));
  }
  std::sort(lateral.begin(), lateral.end());
  const size_t n = lateral.size();
  s.min_radius_m = 0.5 * (lateral[n - 1 - n / 20] - lateral[n / 20]);
  const double reach2 = 4 * o.max_radius_m * o.max_radius_m;
  std::vector<bool> own(map.size(), false);
  for (int i : fitted) own[i] = true;
  for (size_t i = 0; i < map.size(); ++i) {
    if (own[i] || IsTransparent(map[i]) || map[i].removed()) continue;
    const Eigen::Vector3d rel = map[i].position.cast<double>() - s.origin;
    const double h = s.axis.dot(rel);
    if (h > 0 && h <= s.height_m && (rel - h * s.axis).squaredNorm() <= reach2)
      s.solid.push_back(map[i].position.cast<double>());
  }
  return s;
}

// An object whose outline gave its centre and radius (an upright cylinder on its support): its
// surface must lie on that surface and face away from its axis.
bool FitOutline(const std::vector<Surfel>& map, const std::vector<int>& fitted,
                const std::vector<int>& glass, const StandingObject& s, const OutlineFit& fit,
                const RevolutionOptions& o, RevolutionShape* shape, std::vector<Surfel>* out) {
  std::vector<AxisPoint> points;
  for (int i : fitted) {
    const Eigen::Vector3d rel = map[i].position.cast<double>() - s.origin;
    const Eigen::Vector3d n = map[i].normal.cast<double>();
    points.push_back({s.u.dot(rel), s.w.dot(rel), std::max(0.0, s.axis.dot(rel)), s.u.dot(n),
                      s.w.dot(n)});
  }
  const int steps = std::max(1, static_cast<int>(std::ceil(s.height_m / o.height_step_m)));
  const std::vector<double> radius(steps, fit.radius_m);
  MeasureFit(points, fit.centre, radius, o.height_step_m, shape);
  if (shape->residual_m > o.max_residual_m || shape->normal_deg > o.max_normal_angle_deg)
    return false;
  shape->plane_residual_m = static_cast<float>(PlaneResidual(map, fitted, Centre(map, fitted)));
  shape->axis = s.axis.cast<float>();
  shape->standing = true;
  shape->from_outline = true;
  shape->edge_ratio = static_cast<float>(fit.edge_ratio);
  shape->base = (s.origin + fit.centre.x() * s.u + fit.centre.y() * s.w).cast<float>();
  shape->height_m = static_cast<float>(s.height_m);
  shape->radius_m.assign(steps, static_cast<float>(fit.radius_m));
  shape->surfels = static_cast<int>(fitted.size());
  LaySurfels(*shape, s.u.cast<float>(), s.w.cast<float>(), LikeGlass(map, glass, o),
             o.height_step_m, o.spacing_m, out);
  return true;
}

// The outline search draws an object from its support to its top: the object's surfels must
// cover this share of that height or more (a glass read over its front does; a patch of surfels
// that lies at some distance from a wall, "standing" on it, does not).
constexpr double kMinOutlineSpan = 0.5;

// A standing object left to the outline search: its surface, its glass, its frame.
struct Pending {
  std::vector<int> fitted, glass;
  StandingObject standing;
};

// The outline search over the views for the pending objects; those it shapes are added to
// `result` and their surfels marked `seen` (an object whose surface a completed one took is
// skipped).
void FitOutlines(const std::vector<Surfel>& map, const std::vector<Pending>& pending,
                 const Camera& camera, const OutlineViews& views, const RevolutionOptions& o,
                 std::vector<bool>* seen, RevolutionResult* result) {
  std::vector<StandingObject> objects;
  for (const Pending& p : pending) objects.push_back(p.standing);
  OutlineSearchOptions search_options;
  search_options.max_radius_m = o.max_radius_m;
  search_options.height_step_m = o.height_step_m;
  search_options.min_edge_ratio = o.min_edge_ratio;
  OutlineSearch search(std::move(objects), camera, search_options);
  OutlineView view;
  for (size_t i = 0; views(i, &view); ++i) search.AddView(view);
  const std::vector<OutlineFit> fits = search.Fits();
  for (size_t k = 0; k < pending.size(); ++k) {
    const Pending& p = pending[k];
    if (!fits[k].found) continue;
    if (std::any_of(p.fitted.begin(), p.fitted.end(), [&](int i) { return (*seen)[i]; }))
      continue;
    RevolutionShape shape;
    if (!FitOutline(map, p.fitted, p.glass, p.standing, fits[k], o, &shape, &result->surfels))
      continue;
    result->shapes.push_back(std::move(shape));
    for (int i : p.fitted) (*seen)[i] = true;
  }
}

}  // namespace

bool RevolutionOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.Above("cluster_gap_m", cluster_gap_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .In("min_surfels", min_surfels, 3, kMaxImagePixels, kMoreThanAnImagesPixels)
      .In("max_axis_spread", max_axis_spread, 0, 1, kMoreThanOne)
      .Above("min_radius_m", min_radius_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("max_radius_m", max_radius_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Require(min_radius_m <= max_radius_m, "min_radius_m is more than max_radius_m")
      .Above("max_residual_m", max_residual_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .In("max_normal_angle_deg", max_normal_angle_deg, 0, kMaxAngleDeg, kMoreThanAHalfTurn)
      .In("max_residual_share", max_residual_share, 0, 1, kMoreThanOne)
      .In("min_arc_deg", min_arc_deg, 0, 360, "is more than a full turn")
      .Above("height_step_m", height_step_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("spacing_m", spacing_m, 1e-4, kMaxSceneM, kLargerThanAnyScene)
      .Above("support_radius_m", support_radius_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("support_inlier_m", support_inlier_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .In("min_support_share", min_support_share, 0, 1, kMoreThanOne)
      .In("min_support_angle_deg", min_support_angle_deg, 0, 90, "is more than a right angle")
      .In("max_base_gap_m", max_base_gap_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .In("outline_views", outline_views, 0, kMaxFramesInMemory, kMoreFramesThanMemory)
      .Above("min_edge_ratio", min_edge_ratio, 0, 1e6, "is more than a million");
  return c.ok();
}

RevolutionResult FitRevolutions(const std::vector<Surfel>& map, const RevolutionOptions& options,
                                const Camera* camera, const OutlineViews& views) {
  RevolutionResult result;
  if (!options.enabled) return result;
  const std::vector<std::vector<int>> groups = GroupTransparent(map, options.cluster_gap_m);
  std::vector<Eigen::Vector3d> opaque;
  std::unique_ptr<SurfelGrid> all;
  if (options.stand_on_support) {
    for (const Surfel& s : map)
      if (!IsTransparent(s) && !s.removed()) opaque.push_back(s.position.cast<double>());
    if (options.fit_whole_surface)
      all = std::make_unique<SurfelGrid>(map, options.cluster_gap_m,
                                         [](const Surfel&) { return true; });
  }
  std::vector<bool> seen(map.size(), false);  // on the surface of an object completed before
  std::vector<Pending> pending;               // standing objects left to their outlines
  for (const std::vector<int>& whole_group : groups) {
    // The group's surfels that no object completed before took in.
    std::vector<int> group;
    for (int i : whole_group)
      if (!seen[i]) group.push_back(i);
    if (group.empty()) continue;
    Support support;
    std::vector<int> fitted = group;
    // A group of one or two surfels (an outline's flicker) seeds no object on its own.
    if (options.stand_on_support && group.size() >= 3)
      for (const Support& s : CandidateSupports(map, group, opaque, options)) {
        // It stands on the plane when its surface reaches down to it.
        std::vector<int> surface = all ? WholeSurface(map, *all, group, s, options, &seen) : group;
        double lowest = 1e30;
        for (int i : surface) lowest = std::min(lowest, s.Height(map[i].position));
        if (lowest <= options.max_base_gap_m) {
          support = s, fitted = std::move(surface);
          break;
        }
        for (int i : surface) seen[i] = false;  // not this object's surface: free it again
      }
    std::vector<int> glass;
    for (int i : fitted)
      if (IsTransparent(map[i])) glass.push_back(i);
    bool shaped = false;
    if (static_cast<int>(glass.size()) >= options.min_surfels) {
      ++result.objects;
      RevolutionShape shape;
      shaped = FitObject(map, fitted, glass, support, options, &shape, &result.surfels);
      if (shaped)
        result.shapes.push_back(std::move(shape));
      else if (support.found && options.fit_outline && camera && views &&
               std::none_of(pending.begin(), pending.end(),
                            [&](const Pending& p) { return p.fitted == fitted; })) {
        double span = 0;
        StandingObject standing = Standing(map, fitted, support, options, &span);
        if (span >= kMinOutlineSpan) pending.push_back({fitted, glass, std::move(standing)});
      }
    }
    // An object with a shape keeps its surface; a refused one leaves it to the groups after it.
    for (int i : fitted) seen[i] = shaped;
  }
  if (!pending.empty()) FitOutlines(map, pending, *camera, views, options, &seen, &result);
  return result;
}

}  // namespace gf
