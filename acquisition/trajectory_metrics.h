// Trajectory accuracy: absolute trajectory error (ATE) and relative pose error (RPE), as the TUM
// RGB-D benchmark defines them, so figures compare with published ones and with
// ../shared/tools/ate.py.
//
// Association (as ate.py): every estimated pose, in time order, takes the nearest ground-truth pose
// within max_dt (inclusive) that no earlier estimate took. ATE: the estimate is aligned to ground
// truth by the rigid transform (rotation + translation, no scale) that minimises the squared
// position error (Horn / Umeyama), then position errors are summarised. RPE compares the motion
// between consecutive associated frames: translation (metres) and rotation (degrees).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "acquisition/trajectory.h"

namespace gf {

struct TrajectoryErrorOptions {
  double max_dt = 0.02;  // association window, seconds (frame indices for .log trajectories)
  bool Check(std::string* message = nullptr) const;
};

struct TrajectoryErrorSummary {
  bool success = false;  // false when fewer than 3 poses associate
  std::string message;   // why not, when success is false
  int pairs = 0;
  double ate_rmse_m = 0, ate_mean_m = 0, ate_median_m = 0, ate_max_m = 0;
  double rpe_trans_rmse_m = 0;  // per associated frame step
  double rpe_rot_rmse_deg = 0;
  SE3 gt_from_estimate;  // the aligning transform
  std::string BriefReport() const;
};

// (index in gt, index in estimate) pairs, sorted by estimate time.
std::vector<std::pair<size_t, size_t>> AssociatePoses(const Trajectory& gt, const Trajectory& est,
                                                      double max_dt);

// Rigid transform minimising sum |model_i - (R data_i + t)|^2 (Umeyama 1991 without scale).
SE3 AlignPoints(const std::vector<Eigen::Vector3d>& model,
                const std::vector<Eigen::Vector3d>& data);

// The rigid transform that best maps the estimate's camera poses onto the ground truth's, using
// their orientations as well as their positions (the chordal mean of gt_R est_R^T, then the mean
// position offset): unlike AlignPoints on positions alone, well determined when the camera moves
// along a line. For moving a map into the ground truth's frame. Needs >= 1 associated pose; the
// identity otherwise.
SE3 AlignPoses(const Trajectory& gt, const Trajectory& est, double max_dt = 0.02);

TrajectoryErrorSummary EvaluateTrajectory(const Trajectory& gt, const Trajectory& est,
                                          const TrajectoryErrorOptions& options = {});

}  // namespace gf
