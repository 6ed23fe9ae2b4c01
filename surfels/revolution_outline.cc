#include "surfels/revolution_outline.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "acquisition/stats.h"

namespace gf {
namespace {

// The strongest gradient across the direction `normal` (unit, pixels) at the pixel nearest to
// `at` and its neighbours one pixel either way along `normal`.
double EdgeResponse(const cv::Mat& gx, const cv::Mat& gy, const Eigen::Vector2d& at,
                    const Eigen::Vector2d& normal) {
  double best = 0;
  for (int t = -1; t <= 1; ++t) {
    const Eigen::Vector2d p = at + t * normal;
    const int x = static_cast<int>(std::lround(p.x())), y = static_cast<int>(std::lround(p.y()));
    if (x < 0 || y < 0 || x >= gx.cols || y >= gx.rows) continue;
    best =
        std::max(best, std::abs(gx.at<float>(y, x) * normal.x() + gy.at<float>(y, x) * normal.y()));
  }
  return best;
}

}  // namespace

OutlineSearch::OutlineSearch(std::vector<StandingObject> objects, const Camera& camera,
                             const OutlineSearchOptions& options)
    : camera_(camera), options_(options) {
  for (StandingObject& s : objects) {
    Object o;
    o.standing = std::move(s);
    const StandingObject& so = o.standing;
    const Eigen::Vector2d side(-so.outward.y(), so.outward.x());
    const int lateral = static_cast<int>(std::floor(options_.lateral_m / options_.lateral_step_m));
    for (double r = std::max(so.min_radius_m, options_.radius_step_m); r <= options_.max_radius_m;
         r += options_.radius_step_m)
      for (int l = -lateral; l <= lateral; ++l) {
        Hypothesis h;
        h.radius = r;
        h.centre = so.front - r * so.outward + l * options_.lateral_step_m * side;
        int inside = 0;
        const double reach = r - options_.inside_margin_m;
        for (const Eigen::Vector3d& p : so.solid) {
          const Eigen::Vector3d rel = p - so.origin;
          const double height = so.axis.dot(rel);
          if (height < options_.inside_margin_m || height > so.height_m || reach <= 0) continue;
          inside += (Eigen::Vector2d(so.u.dot(rel), so.w.dot(rel)) - h.centre).norm() < reach;
        }
        h.ruled_out = inside > options_.max_solid_inside;
        o.hypotheses.push_back(h);
      }
    objects_.push_back(std::move(o));
  }
}

void OutlineSearch::Score(const Object& o, const SE3& camera_from_world, const Eigen::Vector3d& eye,
                          const cv::Mat& gx, const cv::Mat& gy, Hypothesis* h) const {
  const StandingObject& s = o.standing;
  const Eigen::Vector3d rel = eye - s.origin;
  const Eigen::Vector2d to_eye = Eigen::Vector2d(s.u.dot(rel), s.w.dot(rel)) - h->centre;
  const double d = to_eye.norm();
  if (d <= 1.05 * h->radius) return;  // a camera at the surface sees no outline
  const double facing = std::atan2(to_eye.y(), to_eye.x()), graze = std::acos(h->radius / d);
  const int steps = static_cast<int>(std::floor(s.height_m / options_.height_step_m));
  double sum = 0;
  int samples = 0, missed = 0;
  for (int side = -1; side <= 1; side += 2) {
    const double theta = facing + side * graze;
    const Eigen::Vector2d q =
        h->centre + h->radius * Eigen::Vector2d(std::cos(theta), std::sin(theta));
    const Eigen::Vector3d foot = s.origin + q.x() * s.u + q.y() * s.w;
    // From one step up to one step under the top: the foot and the rim are no outline.
    for (int k = 1; k < steps; ++k) {
      const Eigen::Vector3d p = foot + k * options_.height_step_m * s.axis;
      const Eigen::Vector3d a = camera_from_world * p;
      const Eigen::Vector3d b = camera_from_world * (p + 0.5 * options_.height_step_m * s.axis);
      if (a.z() < 0.1 || b.z() < 0.1) {
        ++missed;
        continue;
      }
      const Eigen::Vector2d pa = camera_.ProjectDistorted(a), pb = camera_.ProjectDistorted(b);
      const Eigen::Vector2d along = pb - pa;
      if (pa.x() < 2 || pa.y() < 2 || pa.x() > gx.cols - 3 || pa.y() > gx.rows - 3 ||
          along.norm() < 1e-6) {
        ++missed;
        continue;
      }
      const Eigen::Vector2d across = Eigen::Vector2d(-along.y(), along.x()).normalized();
      sum += EdgeResponse(gx, gy, pa, across);
      ++samples;
    }
  }
  h->sum += sum;
  h->samples += samples;
  h->views += samples > 0 && samples >= missed;
}

void OutlineSearch::AddView(const OutlineView& view) {
  if (view.image.empty() || objects_.empty()) return;
  cv::Mat gray = view.image;
  if (gray.channels() == 3) cv::cvtColor(view.image, gray, cv::COLOR_BGR2GRAY);
  if (gray.type() != CV_8UC1) return;
  cv::Mat gx, gy;
  cv::Sobel(gray, gx, CV_32F, 1, 0, 3, 1.0 / 8);
  cv::Sobel(gray, gy, CV_32F, 0, 1, 3, 1.0 / 8);
  const SE3 camera_from_world = view.world_from_camera.Inverse();
  const Eigen::Vector3d eye = view.world_from_camera.translation();
  for (Object& o : objects_)
    for (Hypothesis& h : o.hypotheses)
      if (!h.ruled_out) Score(o, camera_from_world, eye, gx, gy, &h);
}

std::vector<OutlineFit> OutlineSearch::Fits() const {
  std::vector<OutlineFit> fits;
  for (const Object& o : objects_) {
    OutlineFit fit;
    std::vector<double> means;
    const Hypothesis* best = nullptr;
    double best_mean = 0;
    for (const Hypothesis& h : o.hypotheses) {
      if (h.ruled_out || h.views < options_.min_views || h.samples == 0) continue;
      const double mean = h.sum / h.samples;
      means.push_back(mean);
      if (!best || mean > best_mean) best = &h, best_mean = mean;
    }
    if (best) {
      const double median = Median(std::move(means));
      fit.centre = best->centre;
      fit.radius_m = best->radius;
      fit.views = best->views;
      fit.edge_ratio = median > 0 ? best_mean / median : 0;
      fit.found = fit.edge_ratio >= options_.min_edge_ratio;
    }
    fits.push_back(fit);
  }
  return fits;
}

}  // namespace gf
