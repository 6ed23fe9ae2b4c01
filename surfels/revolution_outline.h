// The radius of a clear object standing on a support, from its outline in colour images.
//
// The sensor reads clear glass mostly where the surface faces it, so a vase seen from the front
// leaves a narrow upright strip of transparent surfels: over a few centimetres of width a plane
// fits the strip as well as a circle, and the strip alone cannot tell a vase 4 cm wide from one
// 10 cm wide. Its outline can: the edges of a glass against what is behind it are among the
// strongest in a colour image (Phillips et al., RSS 2016, find glassware from its edges), and a
// surface of revolution standing on a known plane has, in every view, two outline lines (the
// generators where the view's rays graze it) whose place depends only on its centre and radius.
//
// Hypotheses: the strip's middle lies on the surface's front, so the centre lies behind it along
// the strip's mean normal by the radius (and up to lateral_m to either side); radii from the
// strip's half width to max_radius_m. Each view adds, for every hypothesis, the colour edge
// response (image gradient across the projected generator, the best within a pixel of it) at
// points along both generators, every height_step_m up the object. A hypothesis that holds an
// opaque surfel of the map inside it (more than a centimetre in from its surface) is ruled out:
// the sensor saw something solid there. The hypothesis with the strongest mean response is the
// object's outline when that response is min_edge_ratio times or more the median hypothesis'
// (a texture's edges line up with no particular outline across views; the glass's do).
//
// No threads, no I/O: the views come one at a time from the caller. Usage:
//   gf::OutlineSearch search(objects, camera, options);
//   for (const gf::OutlineView& v : views) search.AddView(v);
//   std::vector<gf::OutlineFit> fits = search.Fits();
#pragma once

#include <Eigen/Core>
#include <functional>
#include <opencv2/core.hpp>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/se3.h"

namespace gf {

// One colour view: its image (CV_8UC3 BGR or CV_8UC1 grey, the camera's distorted image) and pose.
struct OutlineView {
  cv::Mat image;
  SE3 world_from_camera;
};

// Hands out views one at a time: view `index` into *view; false past the last one.
using OutlineViews = std::function<bool(size_t index, OutlineView* view)>;

// A standing object in its support's frame (world coordinates, metres).
struct StandingObject {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // the support's normal, up
  Eigen::Vector3d u = Eigen::Vector3d::UnitX(), w = Eigen::Vector3d::UnitY();  // across the axis
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();    // on the support; (u, w) coordinates from it
  double height_m = 0;                                 // its top above the support
  Eigen::Vector2d front = Eigen::Vector2d::Zero();     // (u, w) of the read strip's middle
  Eigen::Vector2d outward = Eigen::Vector2d::UnitX();  // unit: the strip's mean normal across
  double min_radius_m = 0;                             // the strip's half width
  std::vector<Eigen::Vector3d> solid;                  // opaque surfels of the map near it (world)
};

struct OutlineSearchOptions {
  double max_radius_m = 0.25;    // widest object, metres
  double radius_step_m = 0.002;  // radii tried, metres apart
  double lateral_m = 0.01;       // the centre may lie this far to either side of the strip's normal
  double lateral_step_m = 0.0025;  // metres between those lateral positions
  double height_step_m = 0.01;     // outline points this far apart up each generator, metres
  // The outline's mean edge response over the median hypothesis', at least (see the file comment).
  double min_edge_ratio = 1.5;
  int min_views = 3;              // views that must see at least half of a hypothesis' outline
  double inside_margin_m = 0.01;  // an opaque surfel this far inside a hypothesis rules it out
  int max_solid_inside = 2;       // ... when more than this many are (a stray fill or two may be)
};

struct OutlineFit {
  bool found = false;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  // (u, w) from origin
  double radius_m = 0;
  double edge_ratio = 0;  // best mean response over the median hypothesis'
  int views = 0;          // views that saw at least half of the best hypothesis' outline
};

class OutlineSearch {
 public:
  OutlineSearch(std::vector<StandingObject> objects, const Camera& camera,
                const OutlineSearchOptions& options);
  void AddView(const OutlineView& view);
  std::vector<OutlineFit> Fits() const;  // one per object, in order

 private:
  struct Hypothesis {
    Eigen::Vector2d centre;
    double radius = 0;
    bool ruled_out = false;
    double sum = 0;  // edge responses
    int samples = 0;
    int views = 0;
  };
  struct Object {
    StandingObject standing;
    std::vector<Hypothesis> hypotheses;
  };
  // Adds one view's responses to hypothesis h of object o (gradients gx, gy: CV_32F).
  void Score(const Object& o, const SE3& camera_from_world, const Eigen::Vector3d& eye,
             const cv::Mat& gx, const cv::Mat& gy, Hypothesis* h) const;
  std::vector<Object> objects_;
  Camera camera_;
  OutlineSearchOptions options_;
};

}  // namespace gf
