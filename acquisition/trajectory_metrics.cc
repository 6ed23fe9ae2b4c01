#include "acquisition/trajectory_metrics.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "acquisition/errors.h"
#include "acquisition/bounds.h"

namespace gf {

bool TrajectoryErrorOptions::Check(std::string* message) const {
  // Seconds, or frame indices for .log trajectories: a day's frames bounds both.
  FieldCheck c(message);
  c.In("max_dt", max_dt, 0, kMaxCaptureFrames, kMoreFramesThanACapture);
  return c.ok();
}

std::string TrajectoryErrorSummary::BriefReport() const {
  if (!success) return "trajectory error: " + message;
  char buffer[256];
  std::snprintf(buffer, sizeof(buffer),
                "ate_rmse_m=%.4f pairs=%d mean=%.4f median=%.4f max=%.4f rpe_trans_m=%.4f "
                "rpe_rot_deg=%.3f",
                ate_rmse_m, pairs, ate_mean_m, ate_median_m, ate_max_m, rpe_trans_rmse_m,
                rpe_rot_rmse_deg);
  return buffer;
}

std::vector<std::pair<size_t, size_t>> AssociatePoses(const Trajectory& gt, const Trajectory& est,
                                                      double max_dt) {
  std::vector<size_t> gt_order(gt.size()), est_order(est.size());
  for (size_t i = 0; i < gt.size(); ++i) gt_order[i] = i;
  for (size_t i = 0; i < est.size(); ++i) est_order[i] = i;
  auto by_time = [](const Trajectory& t) {
    return [&t](size_t a, size_t b) { return t[a].timestamp < t[b].timestamp; };
  };
  std::stable_sort(gt_order.begin(), gt_order.end(), by_time(gt));
  std::stable_sort(est_order.begin(), est_order.end(), by_time(est));
  std::vector<double> gt_times;
  for (size_t i : gt_order) gt_times.push_back(gt[i].timestamp);
  std::set<size_t> used;
  std::vector<std::pair<size_t, size_t>> pairs;
  for (size_t e : est_order) {
    const double t = est[e].timestamp;
    const size_t i = std::lower_bound(gt_times.begin(), gt_times.end(), t) - gt_times.begin();
    long best = -1;
    for (long j : {static_cast<long>(i) - 1, static_cast<long>(i)}) {
      if (j < 0 || j >= static_cast<long>(gt_times.size())) continue;
      if (std::abs(gt_times[j] - t) > max_dt) continue;
      if (best < 0 || std::abs(gt_times[j] - t) < std::abs(gt_times[best] - t)) best = j;
    }
    if (best >= 0 && used.insert(best).second) pairs.emplace_back(gt_order[best], e);
  }
  return pairs;
}

SE3 AlignPoints(const std::vector<Eigen::Vector3d>& model,
                const std::vector<Eigen::Vector3d>& data) {
  GF_CHECK(model.size() == data.size() && model.size() >= 3, "need >= 3 corresponding points");
  Eigen::Vector3d mu_m = Eigen::Vector3d::Zero(), mu_d = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < model.size(); ++i) {
    mu_m += model[i];
    mu_d += data[i];
  }
  mu_m /= model.size();
  mu_d /= data.size();
  Eigen::Matrix3d w = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < model.size(); ++i) w += (model[i] - mu_m) * (data[i] - mu_d).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(w, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d s = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) s(2, 2) = -1;
  const Eigen::Matrix3d r = svd.matrixU() * s * svd.matrixV().transpose();
  return SE3(r, mu_m - r * mu_d);
}

SE3 AlignPoses(const Trajectory& gt, const Trajectory& est, double max_dt) {
  const auto pairs = AssociatePoses(gt, est, max_dt);
  if (pairs.empty()) return SE3();
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  for (const auto& [g, e] : pairs)
    sum += gt[g].world_from_camera.RotationMatrix() *
           est[e].world_from_camera.RotationMatrix().transpose();
  // The rotation nearest the mean (its polar factor).
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d s = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) s(2, 2) = -1;
  const Eigen::Matrix3d r = svd.matrixU() * s * svd.matrixV().transpose();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  for (const auto& [g, e] : pairs)
    t += gt[g].world_from_camera.translation() - r * est[e].world_from_camera.translation();
  return SE3(r, t / static_cast<double>(pairs.size()));
}

TrajectoryErrorSummary EvaluateTrajectory(const Trajectory& gt, const Trajectory& est,
                                          const TrajectoryErrorOptions& options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  TrajectoryErrorSummary s;
  const auto pairs = AssociatePoses(gt, est, options.max_dt);
  s.pairs = static_cast<int>(pairs.size());
  if (pairs.size() < 3) {
    s.message = "only " + std::to_string(pairs.size()) + " associated poses";
    return s;
  }
  std::vector<Eigen::Vector3d> model, data;
  for (const auto& [g, e] : pairs) {
    model.push_back(gt[g].world_from_camera.translation());
    data.push_back(est[e].world_from_camera.translation());
  }
  s.gt_from_estimate = AlignPoints(model, data);
  std::vector<double> errors;
  double sum2 = 0, sum = 0;
  for (size_t i = 0; i < model.size(); ++i) {
    const double err = (s.gt_from_estimate * data[i] - model[i]).norm();
    errors.push_back(err);
    sum += err;
    sum2 += err * err;
  }
  s.ate_rmse_m = std::sqrt(sum2 / errors.size());
  s.ate_mean_m = sum / errors.size();
  s.ate_max_m = *std::max_element(errors.begin(), errors.end());
  std::vector<double> sorted = errors;
  std::sort(sorted.begin(), sorted.end());
  const size_t n = sorted.size();
  s.ate_median_m = n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
  double trans2 = 0, rot2 = 0;
  for (size_t i = 0; i + 1 < pairs.size(); ++i) {
    const SE3 gt_motion =
        gt[pairs[i].first].world_from_camera.Inverse() * gt[pairs[i + 1].first].world_from_camera;
    const SE3 est_motion = est[pairs[i].second].world_from_camera.Inverse() *
                           est[pairs[i + 1].second].world_from_camera;
    const SE3 error = gt_motion.Inverse() * est_motion;
    trans2 += error.translation().squaredNorm();
    const double deg = error.RotationAngle() * 180.0 / M_PI;
    rot2 += deg * deg;
  }
  s.rpe_trans_rmse_m = std::sqrt(trans2 / (pairs.size() - 1));
  s.rpe_rot_rmse_deg = std::sqrt(rot2 / (pairs.size() - 1));
  s.success = true;
  return s;
}

}  // namespace gf
