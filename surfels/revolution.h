// Clear glasses, bottles and vases as surfaces of revolution: the map's transparent surfels
// (FusionOptions::glass) are grouped into objects, and an object whose surfels lie on a surface
// of revolution (a straight axis, a radius that may change with height: a glass, a bottle and its
// neck, a vase) is completed all round, between the lowest and highest of its surfels. The sensor
// reads clear glass where the surface faces it and rarely where the surface turns away, so the
// sides of a glass seen from one place are missing from the map; the circle that the read parts
// lie on gives them (Phillips et al., "Seeing Glassware: from Edge Detection to Pose Estimation
// and Shape Recovery", RSS 2016, recover glassware as surfaces of revolution from one view).
//
// An object standing upright on a plane of the map (a table, a shelf board) takes the plane's
// normal as its axis and is fitted to its whole surface in the map (the glass the sensor read as
// opaque, a label), from the plane up. Otherwise the axis is the direction the surfels' normals
// are all perpendicular to (the normals of a surface of revolution meet its axis); the centre and
// the radius per height come from one linear circle fit (Kasa's) with a shared centre and a radius
// per height step. An object is completed only when its surfels lie within max_residual_m of the
// fitted surface and span min_arc_deg around the axis: a pane (normals all alike), a sphere
// (normals everywhere) or a few surfels on an outline give no axis or no circle and are left as
// they are. A standing object whose read strip is too narrow to tell its curvature may take its
// radius from its outline in colour views (fit_outline, surfels/revolution_outline.h).
//
// No threads, no I/O. Usage:
//   gf::RevolutionResult r = gf::FitRevolutions(fusion.StableSurfels(), options);
//   fusion.AddSurfels(r.surfels);  // transparent surfels all round the accepted objects
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "surfels/revolution_outline.h"
#include "surfels/surfel_map.h"

namespace gf {

struct RevolutionOptions {
  bool enabled = true;
  double cluster_gap_m = 0.02;  // transparent surfels this close (metres) belong to one object
  // An object with fewer transparent surfels gets no shape (evidence that it is clear glass; and
  // a fit to transparent surfels alone has two unknowns for the centre and one per height step).
  int min_surfels = 10;
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
  // Objects stand on a support (Phillips et al.: glassware upright on a table): the largest
  // planes of the map's other surfels within support_radius_m (metres) of an object, each
  // holding min_support_share of those surfels or more (within support_inlier_m, metres), are
  // its candidates: the object lies above it, its normals a median of min_support_angle_deg or
  // more from the plane's (a glass's side is upright; a pane's normals are its wall's). It stands
  // on the first, most nearly perpendicular to its normals, that its surface reaches down to
  // (its lowest surfel at most max_base_gap_m, metres, up: the sensor rarely reads a glass's
  // foot, and may read a bottle's glass only above its label). A standing object's axis is the
  // support's normal and its surface reaches down to the support. Off (or no support found): the
  // axis from the normals alone, the surface between the lowest and highest transparent surfel.
  bool stand_on_support = true;
  // A standing object is fitted to every surfel of the map on its surface (any source: the
  // sensor's readings of the glass that stayed opaque, a bottle's label), reached from its
  // transparent surfels over gaps of cluster_gap_m, above its support, within max_radius_m of
  // their centre across the axis; min_surfels counts the transparent ones among them. A surfel
  // belongs to one completed object at most (a refused object's surface is left to the groups
  // after it). Off: its transparent surfels alone.
  bool fit_whole_surface = true;
  double support_radius_m = 0.3;
  double support_inlier_m = 0.01;
  double min_support_share = 0.1;
  double min_support_angle_deg = 60;
  double max_base_gap_m = 0.1;
  // A standing object refused above (a narrow strip of a vase seen from the front fits a plane as
  // well as a circle) takes its radius from its outline in colour views of the run, when views
  // are given (surfels/revolution_outline.h): the outline whose edges stand out min_edge_ratio
  // times over the median hypothesis' in outline_views keyframes (evenly spaced over the run; the
  // pipeline reads them), at least three of which see half of it or more. Its surfels must then
  // lie on the upright cylinder found (max_residual_m, max_normal_angle_deg). Off: such objects
  // are left as they are.
  bool fit_outline = true;
  int outline_views = 24;
  double min_edge_ratio = 1.5;
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field.
  bool Check(std::string* message = nullptr) const;
};

// One object completed as a surface of revolution (world frame).
struct RevolutionShape {
  Eigen::Vector3f axis = Eigen::Vector3f::UnitZ();  // unit
  // The axis on the support (standing), or at the lowest surfel's height.
  Eigen::Vector3f base = Eigen::Vector3f::Zero();
  float height_m = 0;           // from base along the axis
  std::vector<float> radius_m;  // per height_step_m from base, metres
  int surfels = 0;              // surfels it was fitted to (the whole surface, when standing)
  float residual_m = 0;         // their median distance from the surface
  float normal_deg = 0;         // their normals' median angle from the surface's
  float plane_residual_m = 0;   // their median distance from the plane that fits them best
  float arc_deg = 0;            // how far round the axis they reach
  bool standing = false;        // on a support: base on it, axis its normal
  bool from_outline = false;    // its radius from its outline in colour views (fit_outline)
  float edge_ratio = 0;         // ... the outline's edge response over the median hypothesis'
};

struct RevolutionResult {
  // Objects tried: surfaces holding min_surfels transparent surfels or more (a refused one may be
  // tried again from another of its groups).
  int objects = 0;
  std::vector<RevolutionShape> shapes;  // the accepted ones
  std::vector<Surfel> surfels;          // laid on them: source kTransparent
};

// `camera` and `views` (may be empty): colour views of the scene for fit_outline.
RevolutionResult FitRevolutions(const std::vector<Surfel>& map, const RevolutionOptions& options,
                                const Camera* camera = nullptr, const OutlineViews& views = {});

}  // namespace gf
