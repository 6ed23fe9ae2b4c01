// The loop-closure stage's corrections of tracked poses, shared with the fusion stage and the end
// of the run.
//
// Tracking keeps its own (odometry) world frame. After the pose graph is optimised, keyframe k's
// correction is C(k) = world_from_keyframe_k (optimised) * world_from_keyframe_k (tracked)^-1, and
// every frame tracked against keyframe k moves to C(k) * world_from_camera (tracked). Keyframes
// newer than the graph's last optimisation take the correction of the newest keyframe before them
// (tracking goes on from where the graph left it).
//
// Thread-safety: every method may be called from any thread.
#pragma once

#include <map>
#include <mutex>

#include "acquisition/se3.h"

namespace gf {

class PoseCorrections {
 public:
  // Replaces the corrections (keyed by keyframe id) and bumps the version.
  void Publish(std::map<int, SE3> corrections) {
    std::lock_guard<std::mutex> lock(mutex_);
    corrections_ = std::move(corrections);
    ++version_;
  }
  // C(keyframe): that of the newest keyframe at or before it; identity before any.
  SE3 Correction(int keyframe) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return Lookup(corrections_, keyframe);
  }
  int version() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return version_;
  }
  std::map<int, SE3> Snapshot(int* version = nullptr) const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (version) *version = version_;
    return corrections_;
  }
  // The same rule over a snapshot.
  static SE3 Lookup(const std::map<int, SE3>& corrections, int keyframe) {
    auto it = corrections.upper_bound(keyframe);
    if (it == corrections.begin()) return SE3();
    return std::prev(it)->second;
  }

 private:
  mutable std::mutex mutex_;
  std::map<int, SE3> corrections_;
  int version_ = 0;
};

}  // namespace gf
