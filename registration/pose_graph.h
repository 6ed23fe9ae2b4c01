// A pose graph of keyframes, optimised with Ceres: the back end of loop closure.
//
// Nodes are keyframe poses world_from_keyframe (a unit quaternion on Ceres' EigenQuaternionManifold
// and a translation). An edge is a measured relative pose from_from_to (the alignment of keyframe
// `to` against keyframe `from`) with the information matrix of that alignment, for a perturbation
// applied on the left, xi = [rho; phi] (metres, radians):
//   measured = exp(xi) * true,  xi ~ N(0, information^-1).
// Its residual is the left error of the estimate, E = (world_from_from^-1 world_from_to)
// measured^-1, as [translation of E; 2 vec(quaternion of E)] (= log E to first order), whitened
// by the square root of the information. Odometry edges enter as they are; loop edges through a
// Huber loss. After optimising, loop edges whose whitened squared residual exceeds
// max_loop_chi2 (3 sigma of a chi-square with 6 degrees of freedom: 20.06) are implausible
// (RTAB-Map's rule); the worst is rejected and the graph re-optimised, until none remains.
// The first node is held fixed (the world frame is the first keyframe's), and so is every node
// the caller holds (Hold): a solve moves only the other nodes, over the edges that touch one of
// them, so its cost follows the nodes left free, not the graph's size.
//
// No threads, no I/O. Usage:
//   gf::PoseGraph graph;
//   graph.AddNode(0, gf::SE3());
//   graph.AddNode(1, world_from_1);
//   graph.AddEdge({0, 1, kf0_from_kf1, information, gf::PoseGraphEdge::Kind::kOdometry});
//   gf::PoseGraphSummary s = graph.Optimize({});
//   gf::SE3 corrected = graph.pose(1);
#pragma once

#include <Eigen/Core>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "acquisition/se3.h"

namespace gf {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

struct PoseGraphEdge {
  enum class Kind {
    kOdometry,        // consecutive keyframes, from tracking
    kLoop,            // a verified loop closure
    kRelocalisation,  // tracking lost, then found again against an earlier keyframe
    kGap,             // tracking lost and restarted at the last good pose: a weak guess
  };
  int from = 0, to = 0;                         // node ids
  SE3 from_from_to;                             // measured pose of `to` in `from`'s frame
  Matrix6d information = Matrix6d::Identity();  // of a left perturbation [rho; phi]
  Kind kind = Kind::kOdometry;
  bool rejected = false;  // by the graph's plausibility test (loop edges only)
  double chi2 = 0;        // whitened squared residual after the last optimisation
};
const char* EdgeKindName(PoseGraphEdge::Kind kind);

struct PoseGraphOptions {
  // A loop edge whose whitened squared residual exceeds this after optimising is rejected (the
  // chi-square distribution with 6 degrees of freedom stays below 20.06 with 99.73% probability).
  double max_loop_chi2 = 20.06;
  // Loop edges are robustified by a Huber loss of this scale, in whitened units (sigmas).
  double loop_huber = 3.0;
  int max_iterations = 100;  // Levenberg-Marquardt iterations per solve
  int max_rejections = 10;   // loop edges rejected (and re-solves) per Optimize() at most
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

struct PoseGraphSummary {
  bool success = false;
  std::string termination;                   // Ceres' message, or why it was not run
  int nodes = 0, edges = 0, loop_edges = 0;  // in the solve (nodes: those free to move)
  int held = 0;                              // nodes held at their estimates
  int solves = 0, iterations = 0;
  int rejected = 0;  // loop edges rejected by this call
  double initial_cost = 0, final_cost = 0;
  double ms = 0;
  std::string BriefReport() const;
};

// What an alignment's own information leaves out, as standard deviations per axis added to its
// covariance (InformationWithFloor): a floor, and a bias that grows with the change of viewpoint.
// A depth error fixed in the image (the sensor's calibration, its depth distortion) does not cancel
// between two views that see a surface at different pixels; its effect on their alignment grows
// with how far the scene moves across the image, measured at the scene's depth:
// v = |t| + depth * angle (metres). Then sigma = floor_m + bias * v (metres) and
// floor_deg + bias * v / depth (radians, in degrees).
struct AlignmentNoise {
  double floor_m = 0.003;  // per translation axis, metres
  double floor_deg = 0.2;  // per rotation axis, degrees
  // Standard deviation per metre of viewpoint change (dimensionless). 0.1: on tum_fr1_xyz_head,
  // against the ground truth, loop edges were off by about 2 cm at about 14 cm of viewpoint change
  // (0.15) and consecutive keyframes by 3 mm at 4.4 cm (0.07).
  // At most 10: a deviation ten times the viewpoint change constrains nothing.
  double bias = 0.1;
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};
// The information of an alignment of `relative` (over a scene about scene_depth_m away) with
// AlignmentNoise added.
Matrix6d AlignmentInformation(const Matrix6d& alignment_information, const SE3& relative,
                              double scene_depth_m, const AlignmentNoise& noise);

// The information of an alignment whose own information (J^T W J of its whitened residuals) is
// `alignment_information`, with the errors its residual model leaves out added to its covariance:
// sigma_m (metres) on each translation axis and sigma_rad (radians) on each rotation axis.
// Directions the alignment does not constrain (near-zero eigenvalues) stay unconstrained.
Matrix6d InformationWithFloor(const Matrix6d& alignment_information, double sigma_m,
                              double sigma_rad);

class PoseGraph {
 public:
  // Adds a node with its initial estimate (ids need not be dense); re-adding replaces the estimate.
  void AddNode(int id, const SE3& world_from_node);
  // Both nodes must exist (throws std::logic_error otherwise).
  void AddEdge(const PoseGraphEdge& edge);
  bool HasNode(int id) const { return poses_.count(id) != 0; }
  const SE3& pose(int id) const;
  void SetPose(int id, const SE3& world_from_node);
  // Holds a node at its current estimate in every later Optimize() (the node must exist).
  void Hold(int id);
  bool held(int id) const { return held_.count(id) != 0; }
  int held_count() const { return static_cast<int>(held_.size()); }
  const std::map<int, SE3>& poses() const { return poses_; }
  const std::vector<PoseGraphEdge>& edges() const { return edges_; }
  // Solves from the current estimates; the first node (smallest id) and the held ones stay fixed.
  PoseGraphSummary Optimize(const PoseGraphOptions& options);
  // Whitened squared residual of an edge at the current estimates.
  double Chi2(const PoseGraphEdge& edge) const;
  // The nodes at most `max_edges` edges from `id` (itself included), through the edges that
  // measure a relative pose (odometry, relocalisation and loops the graph kept; not gap guesses).
  std::set<int> NodesWithin(int id, int max_edges) const;

 private:
  // Ceres parameter blocks: quaternion (x, y, z, w) and translation per node.
  struct Block {
    double q[4];
    double t[3];
  };
  PoseGraphSummary Solve(const PoseGraphOptions& options, std::map<int, Block>* blocks);
  bool Free(int id) const { return id != poses_.begin()->first && !held(id); }
  bool InSolve(const PoseGraphEdge& e) const { return !e.rejected && (Free(e.from) || Free(e.to)); }
  std::map<int, SE3> poses_;
  std::vector<PoseGraphEdge> edges_;
  std::set<int> held_;
};

}  // namespace gf
