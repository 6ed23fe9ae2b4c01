// Clear glasses, bottles and vases as surfaces of revolution: the map's transparent surfels
// (FusionOptions::glass) are grouped into objects, and an object whose surfels lie on a surface
// of revolution (a straight axis, a radius that may change with height: a glass, a bottle and its
// neck, a vase) is completed all round, between the lowest and highest of its surfels. The sensor
// reads clear glass where the surface faces it and rarely where the surface turns away, so the
// sides of a glass seen from one place are missing from the map; the circle that the read parts
// lie on gives them (Phillips et al., "Seeing Glassware: from Edge Detection to Pose Estimation
// and Shape Recovery", RSS 2016, recover glassware as surfaces of revolution from one view).
//
// The axis is the direction the surfels' normals are all perpendicular to (the normals of a
// surface of revolution meet its axis); the centre and the radius per height come from one
// linear circle fit (Kasa's) with a shared centre and a radius per height step. An object is
// completed only when its surfels lie within max_residual_m of the fitted surface and span
// min_arc_deg around the axis: a pane (normals all alike), a sphere (normals everywhere) or a few
// surfels on an outline give no axis or no circle and are left as they are.
//
// No threads, no I/O. Usage:
//   gf::RevolutionResult r = gf::FitRevolutions(fusion.StableSurfels(), options);
//   fusion.AddSurfels(r.surfels);  // transparent surfels all round the accepted objects
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "surfels/surfel_map.h"

namespace gf {

struct RevolutionOptions {
  bool enabled = true;
  double cluster_gap_m = 0.02;  // transparent surfels this close (metres) belong to one object
  // An object with fewer transparent surfels gets no shape (the fit has two unknowns for the
  // centre and one per height step).
  int min_surfels = 20;
  // The smallest eigenvalue of the normals' scatter over the middle one, at most: the normals lie
  // near a plane, the one perpendicular to the axis (a cylinder's give the noise of its normals;
  // a sphere's, the same in every direction, about 1).
  double max_axis_spread = 0.5;
  double min_radius_m = 0.01;  // a surface of revolution is at least this thick (radius, metres)
  double max_radius_m = 0.25;  // ... and at most this (a glass, a bottle, a vase)
  // Median distance of the object's surfels from the fitted surface, metres, at most: the
  // sensor's noise on glass, a few millimetres.
  double max_residual_m = 0.005;
  // Median angle between the surfels' normals and the fitted surface's, across the axis, at most
  // (degrees): the surfels face away from the axis as a glass's outside does. A flat patch that
  // a small circle happens to pass near has its normals all alike, at any angle to the circle's.
  double max_normal_angle_deg = 30;
  // The fitted surface's residual over that of the best plane through the same surfels, at most:
  // the curvature must explain most of what a plane leaves (a flat patch fits a circle no better
  // than a plane; the front of a 4 cm glass seen over 75 degrees leaves a plane 7 mm of sag).
  double max_residual_share = 0.5;
  // The surfels must reach this far round the axis, degrees: over a sixth of a turn the arc's
  // depth (r (1 - cos 30 degrees), 5 mm for a 4 cm glass) stands above the sensor's noise.
  double min_arc_deg = 60;
  double height_step_m = 0.01;  // the radius is fitted per step of this height, metres
  double spacing_m = 0.005;     // between the surfels laid on the completed surface, metres
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field.
  bool Check(std::string* message = nullptr) const;
};

// One object completed as a surface of revolution (world frame).
struct RevolutionShape {
  Eigen::Vector3f axis = Eigen::Vector3f::UnitZ();  // unit
  Eigen::Vector3f base = Eigen::Vector3f::Zero();   // the axis at the lowest surfel's height
  float height_m = 0;                               // from base along the axis
  std::vector<float> radius_m;                      // per height_step_m from base, metres
  int surfels = 0;                                  // transparent surfels it was fitted to
  float residual_m = 0;                             // their median distance from the surface
  float normal_deg = 0;        // their normals' median angle from the surface's
  float plane_residual_m = 0;  // their median distance from the plane that fits them best
  float arc_deg = 0;           // how far round the axis they reach
};

struct RevolutionResult {
  int objects = 0;                      // groups of transparent surfels with min_surfels or more
  std::vector<RevolutionShape> shapes;  // the accepted ones
  std::vector<Surfel> surfels;          // laid on them: source kTransparent
};

RevolutionResult FitRevolutions(const std::vector<Surfel>& map, const RevolutionOptions& options);

}  // namespace gf
