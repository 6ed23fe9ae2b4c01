// Circles about an axis for surfels/revolution.cc (not an API of its own): a Kasa circle fit
// with a shared centre and a radius per height step, and how well a fit holds its points.
//
// No threads, no I/O.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "surfels/revolution.h"

namespace gf::revolution_detail {

// A surfel of the object in the axis' frame: (x, y) across the axis, h along it from the lowest
// surfel; (nx, ny) its normal across the axis.
struct AxisPoint {
  double x, y, h, nx, ny;
};

// Kasa's circle fit with one centre and one radius per height step: x^2 + y^2 = a x + b y + k_s,
// linear in (a, b, k_s); centre (a/2, b/2), r_s^2 = k_s + |centre|^2. Steps with fewer than
// three points get the radius of the nearest step that has them. False when a radius is not real.
bool FitCircles(const std::vector<AxisPoint>& points, int steps, double step_m,
                Eigen::Vector2d* centre, std::vector<double>* radius);

// The median distance of the points from the fitted surface, the median angle (degrees) between
// their normals and the surface's (away from the axis) across the axis, and the arc they span
// (degrees).
void MeasureFit(const std::vector<AxisPoint>& points, const Eigen::Vector2d& centre,
                const std::vector<double>& radius, double step_m, RevolutionShape* shape);

}  // namespace gf::revolution_detail
