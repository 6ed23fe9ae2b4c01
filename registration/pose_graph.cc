#include "registration/pose_graph.h"

#include <ceres/ceres.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <vector>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"
#include "registration/pose_graph_cost.h"

namespace gf {

const char* EdgeKindName(PoseGraphEdge::Kind kind) {
  switch (kind) {
    case PoseGraphEdge::Kind::kOdometry:
      return "odometry";
    case PoseGraphEdge::Kind::kLoop:
      return "loop";
    case PoseGraphEdge::Kind::kRelocalisation:
      return "relocalisation";
    case PoseGraphEdge::Kind::kGap:
      return "gap";
  }
  return "unknown";
}

bool PoseGraphOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.Above("max_loop_chi2", max_loop_chi2, 0, kMaxSigmas * kMaxSigmas,
          "is a squared residual of more standard deviations than any measurement lies out")
      .Above("loop_huber", loop_huber, 0, kMaxSigmas, kMoreSigmasThanMeasurable)
      .In("max_iterations", max_iterations, 1, kMaxIterations, kMoreIterationsThanAFrameAllows)
      // Each rejection removes one loop edge, at most one per keyframe.
      .In("max_rejections", max_rejections, 0, kMaxCaptureFrames, kMoreFramesThanACapture);
  return c.ok();
}

std::string PoseGraphSummary::BriefReport() const {
  char buffer[240];
  std::snprintf(buffer, sizeof(buffer),
                "pose graph %s (%s): %d nodes free, %d held, %d edges (%d loops), %d solves, "
                "%d iterations, cost %.4g -> %.4g, %d loops rejected, %.1f ms",
                success ? "ok" : "failed", termination.c_str(), nodes, held, edges, loop_edges,
                solves, iterations, initial_cost, final_cost, rejected, ms);
  return buffer;
}

Matrix6d InformationWithFloor(const Matrix6d& alignment_information, double sigma_m,
                              double sigma_rad) {
  // Covariance of the alignment: the pseudo-inverse of its information, with directions of
  // (numerically) no information left at a variance far beyond any scene (1e6: a kilometre).
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eigen(
      0.5 * (alignment_information + alignment_information.transpose()));
  Eigen::Matrix<double, 6, 1> variances;
  for (int i = 0; i < 6; ++i) {
    const double lambda = eigen.eigenvalues()(i);
    variances(i) = lambda > 1e-6 ? std::min(1.0 / lambda, 1e6) : 1e6;
  }
  Matrix6d covariance =
      eigen.eigenvectors() * variances.asDiagonal() * eigen.eigenvectors().transpose();
  for (int i = 0; i < 3; ++i) {
    covariance(i, i) += sigma_m * sigma_m;
    covariance(i + 3, i + 3) += sigma_rad * sigma_rad;
  }
  const Matrix6d information = covariance.inverse();
  return 0.5 * (information + information.transpose());
}

bool AlignmentNoise::Check(std::string* message) const {
  // bias 10: a standard deviation of ten times the viewpoint change, an edge that constrains
  // nothing the scene's size does not.
  FieldCheck c(message);
  c.Above("floor_m", floor_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("floor_deg", floor_deg, 0, kMaxAngleDeg, kMoreThanAHalfTurn)
      .In("bias", bias, 0, 10,
          "is a standard deviation of more than ten times the viewpoint "
          "change");
  return c.ok();
}

Matrix6d AlignmentInformation(const Matrix6d& alignment_information, const SE3& relative,
                              double scene_depth_m, const AlignmentNoise& noise) {
  const double depth = std::max(scene_depth_m, 0.1);
  const double viewpoint_change = relative.TranslationNorm() + depth * relative.RotationAngle();
  const double sigma_m = noise.floor_m + noise.bias * viewpoint_change;
  const double sigma_rad = noise.floor_deg * M_PI / 180.0 + noise.bias * viewpoint_change / depth;
  return InformationWithFloor(alignment_information, sigma_m, sigma_rad);
}

void PoseGraph::AddNode(int id, const SE3& world_from_node) { poses_[id] = world_from_node; }

void PoseGraph::AddEdge(const PoseGraphEdge& edge) {
  GF_CHECK(HasNode(edge.from) && HasNode(edge.to) && edge.from != edge.to,
           "a pose-graph edge needs two distinct existing nodes");
  GF_CHECK(edge.information.allFinite(), "a pose-graph edge needs a finite information matrix");
  edges_.push_back(edge);
}

const SE3& PoseGraph::pose(int id) const {
  const auto it = poses_.find(id);
  GF_CHECK(it != poses_.end(), "no such pose-graph node");
  return it->second;
}

void PoseGraph::Hold(int id) {
  GF_CHECK(HasNode(id), "no such pose-graph node");
  held_.insert(id);
}

std::set<int> PoseGraph::NodesWithin(int id, int max_edges) const {
  std::map<int, std::vector<int>> neighbours;
  for (const PoseGraphEdge& e : edges_) {
    if (e.rejected || e.kind == PoseGraphEdge::Kind::kGap) continue;
    neighbours[e.from].push_back(e.to);
    neighbours[e.to].push_back(e.from);
  }
  std::set<int> reached = {id};
  std::vector<int> ring = {id};
  for (int step = 0; step < max_edges && !ring.empty(); ++step) {
    std::vector<int> next;
    for (int node : ring)
      for (int n : neighbours[node])
        if (reached.insert(n).second) next.push_back(n);
    ring = std::move(next);
  }
  return reached;
}

void PoseGraph::SetPose(int id, const SE3& world_from_node) {
  GF_CHECK(HasNode(id), "no such pose-graph node");
  poses_[id] = world_from_node;
}

double PoseGraph::Chi2(const PoseGraphEdge& edge) const {
  const RelativePoseError cost(edge.from_from_to, edge.information);
  const SE3& a = pose(edge.from);
  const SE3& b = pose(edge.to);
  const Eigen::Vector4d qa = a.rotation().coeffs(), qb = b.rotation().coeffs();
  Eigen::Matrix<double, 6, 1> r;
  cost(qa.data(), a.translation().data(), qb.data(), b.translation().data(), r.data());
  return r.squaredNorm();
}

PoseGraphSummary PoseGraph::Solve(const PoseGraphOptions& options, std::map<int, Block>* blocks) {
  ceres::Problem problem;
  for (auto& [id, block] : *blocks) {
    problem.AddParameterBlock(block.q, 4, new ceres::EigenQuaternionManifold);
    problem.AddParameterBlock(block.t, 3);
    if (!Free(id)) {
      problem.SetParameterBlockConstant(block.q);
      problem.SetParameterBlockConstant(block.t);
    }
  }
  PoseGraphSummary s;
  for (const PoseGraphEdge& e : edges_) {
    if (!InSolve(e)) continue;
    const bool loop = e.kind == PoseGraphEdge::Kind::kLoop;
    ceres::LossFunction* loss = loop ? new ceres::HuberLoss(options.loop_huber) : nullptr;
    Block& a = blocks->at(e.from);
    Block& b = blocks->at(e.to);
    problem.AddResidualBlock(RelativePoseError::Create(e.from_from_to, e.information), loss, a.q,
                             a.t, b.q, b.t);
    ++s.edges;
    s.loop_edges += loop;
  }
  ceres::Solver::Options solver;
  solver.max_num_iterations = options.max_iterations;
  solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver.num_threads = 1;  // algorithms own no threads
  solver.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  s.success = summary.IsSolutionUsable();
  s.termination = summary.message;
  s.iterations = static_cast<int>(summary.iterations.size());
  s.initial_cost = summary.initial_cost;
  s.final_cost = summary.final_cost;
  return s;
}

PoseGraphSummary PoseGraph::Optimize(const PoseGraphOptions& options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  const auto start = std::chrono::steady_clock::now();
  PoseGraphSummary total;
  total.held = static_cast<int>(held_.size());
  for (const auto& [id, pose] : poses_) total.nodes += Free(id);
  if (poses_.size() < 2 || edges_.empty()) {
    total.success = true;
    total.termination = "nothing to optimise";
    return total;
  }
  // Each solve starts from the estimates before this call, so a rejected edge leaves no trace.
  const std::map<int, SE3> initial = poses_;
  for (int round = 0;; ++round) {
    std::map<int, Block> blocks;  // the nodes of the edges in the solve
    poses_ = initial;
    for (const PoseGraphEdge& e : edges_) {
      if (!InSolve(e)) continue;
      for (const int id : {e.from, e.to}) {
        Block& b = blocks[id];
        Eigen::Map<Eigen::Vector4d>(b.q) = poses_.at(id).rotation().coeffs();
        Eigen::Map<Eigen::Vector3d>(b.t) = poses_.at(id).translation();
      }
    }
    if (blocks.empty()) {  // every edge between held nodes
      total.success = true;
      total.termination = "nothing free to optimise";
      break;
    }
    const PoseGraphSummary s = Solve(options, &blocks);
    if (round == 0) total.initial_cost = s.initial_cost;
    total.final_cost = s.final_cost;
    total.iterations += s.iterations;
    total.edges = s.edges;
    total.loop_edges = s.loop_edges;
    total.termination = s.termination;
    ++total.solves;
    if (!s.success) return total;  // estimates unchanged
    for (const auto& [id, b] : blocks)
      poses_[id] = SE3(Eigen::Quaterniond(b.q[3], b.q[0], b.q[1], b.q[2]),
                       Eigen::Vector3d(b.t[0], b.t[1], b.t[2]));
    // The least plausible loop edge beyond the test is rejected, and the graph solved again.
    PoseGraphEdge* worst = nullptr;
    for (PoseGraphEdge& e : edges_) {
      if (!InSolve(e)) continue;
      e.chi2 = Chi2(e);
      if (e.kind == PoseGraphEdge::Kind::kLoop && e.chi2 > options.max_loop_chi2 &&
          (!worst || e.chi2 > worst->chi2))
        worst = &e;
    }
    total.success = true;
    if (!worst || round >= options.max_rejections) break;
    worst->rejected = true;
    ++total.rejected;
  }
  total.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return total;
}

}  // namespace gf
