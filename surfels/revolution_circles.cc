#include "surfels/revolution_circles.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "acquisition/stats.h"

namespace gf::revolution_detail {

constexpr double kTwoPi = 2 * M_PI;

// Kasa's circle fit with one centre and one radius per height step: x^2 + y^2 = a x + b y + k_s,
// linear in (a, b, k_s); centre (a/2, b/2), r_s^2 = k_s + |centre|^2. Steps with fewer than
// three points get the radius of the nearest step that has them. False when a radius is not real.
bool FitCircles(const std::vector<AxisPoint>& points, int steps, double step_m,
                Eigen::Vector2d* centre, std::vector<double>* radius) {
  std::vector<int> count(steps, 0), column(steps, -1);
  for (const AxisPoint& p : points) ++count[std::min(steps - 1, static_cast<int>(p.h / step_m))];
  int columns = 2;
  for (int s = 0; s < steps; ++s)
    if (count[s] >= 3) column[s] = columns++;
  if (columns == 2) return false;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(columns, columns);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(columns);
  for (const AxisPoint& p : points) {
    const int c = column[std::min(steps - 1, static_cast<int>(p.h / step_m))];
    if (c < 0) continue;
    Eigen::VectorXd row = Eigen::VectorXd::Zero(columns);
    row(0) = p.x, row(1) = p.y, row(c) = 1;
    a += row * row.transpose();
    rhs += row * (p.x * p.x + p.y * p.y);
  }
  const Eigen::VectorXd solution = a.ldlt().solve(rhs);
  if (!solution.allFinite()) return false;
  *centre = 0.5 * solution.head<2>();
  radius->assign(steps, -1);
  for (int s = 0; s < steps; ++s) {
    if (column[s] < 0) continue;
    const double r2 = solution(column[s]) + centre->squaredNorm();
    if (!(r2 > 0)) return false;
    (*radius)[s] = std::sqrt(r2);
  }
  for (int s = 0; s < steps; ++s) {  // empty steps: the nearest fitted one
    if ((*radius)[s] >= 0) continue;
    for (int d = 1; d < steps; ++d) {
      if (s - d >= 0 && column[s - d] >= 0) {
        (*radius)[s] = (*radius)[s - d];
        break;
      }
      if (s + d < steps && column[s + d] >= 0) {
        (*radius)[s] = (*radius)[s + d];
        break;
      }
    }
  }
  return true;
}

// The median distance of the points from the fitted surface, the median angle (degrees) between
// their normals and the surface's (away from the axis) across the axis, and the arc they span
// (degrees).
void MeasureFit(const std::vector<AxisPoint>& points, const Eigen::Vector2d& centre,
                const std::vector<double>& radius, double step_m, RevolutionShape* shape) {
  std::vector<double> off, turn, angle;
  for (const AxisPoint& p : points) {
    const int s = std::min(static_cast<int>(radius.size()) - 1, static_cast<int>(p.h / step_m));
    const Eigen::Vector2d d(p.x - centre.x(), p.y - centre.y()), n(p.nx, p.ny);
    off.push_back(std::abs(d.norm() - radius[s]));
    const double c = n.norm() > 1e-6 ? d.normalized().dot(n.normalized()) : -1.0;
    turn.push_back(std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / M_PI);
    angle.push_back(std::atan2(d.y(), d.x()));
  }
  shape->residual_m = static_cast<float>(Median(off));
  shape->normal_deg = static_cast<float>(Median(turn));
  std::sort(angle.begin(), angle.end());
  double widest_gap = kTwoPi - (angle.back() - angle.front());
  for (size_t i = 1; i < angle.size(); ++i)
    widest_gap = std::max(widest_gap, angle[i] - angle[i - 1]);
  shape->arc_deg = static_cast<float>((kTwoPi - widest_gap) * 180.0 / M_PI);
}

}  // namespace gf::revolution_detail
