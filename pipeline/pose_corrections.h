// The loop-closure stage's corrections of tracked poses, shared with the fusion stage and the end
// of the run.
//
// Tracking keeps its own (odometry) world frame. After the pose graph is optimised, keyframe k's
// correction is C(k) = world_from_keyframe_k (optimised) * world_from_keyframe_k (tracked)^-1, and
// every frame tracked against keyframe k moves to C(k) * world_from_camera (tracked). Keyframes
// newer than the graph's last optimisation take the correction of the newest keyframe before them
// (tracking goes on from where the graph left it).
//
// Fixed points of the keyframe sequence (reproducible runs): the loop stage publishes while it
// processes its keyframes in order and says when each is done (MarkProcessed). AtProcessed(n)
// waits until the first n keyframes are done and gives the corrections as they stood then, so a
// reader that asks at the same n gets the same corrections however fast the loop thread ran.
// Snapshot() gives the newest (live input, the end of a run). The history AtProcessed needs is kept
// only after RecordHistory(true) (live input never asks for it).
//
// Thread-safety: every method may be called from any thread.
#pragma once

#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include "acquisition/se3.h"

namespace gf {

class PoseCorrections {
 public:
  // Replaces the corrections (keyed by keyframe id) and bumps the version. Published while the
  // writer works on its (processed + 1)-th keyframe, they belong to that keyframe.
  void Publish(std::map<int, SE3> corrections) {
    std::lock_guard<std::mutex> lock(mutex_);
    corrections_ = std::make_shared<const std::map<int, SE3>>(std::move(corrections));
    ++version_;
    if (record_history_) history_.push_back({processed_ + 1, version_, corrections_});
  }
  // Before the writer starts: keep what AtProcessed needs.
  void RecordHistory(bool on) {
    std::lock_guard<std::mutex> lock(mutex_);
    record_history_ = on;
  }
  // The writer has processed its first n keyframes (n grows by one at a time).
  void MarkProcessed(int n) {
    std::lock_guard<std::mutex> lock(mutex_);
    processed_ = n;
    changed_.notify_all();
  }
  // No more keyframes will be processed (the writer ended, finished or stopped).
  void Close() {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    changed_.notify_all();
  }
  // Waits until the first n keyframes are processed (or Close(), or `give_up`, asked every 50 ms,
  // returns true); returns the corrections published while the first n were processed, and sets
  // *version to theirs (0: none yet). Asked with non-decreasing n (history before the answer is
  // forgotten).
  std::map<int, SE3> AtProcessed(int n, int* version, const std::function<bool()>& give_up = {}) {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!changed_.wait_for(lock, std::chrono::milliseconds(50),
                              [&] { return closed_ || processed_ >= n; }))
      if (give_up && give_up()) break;
    size_t last = history_.size();  // the newest publication that belongs to keyframe <= n
    for (size_t i = 0; i < history_.size() && history_[i].keyframe <= n; ++i) last = i;
    if (last == history_.size()) {
      *version = 0;
      return {};
    }
    history_.erase(history_.begin(), history_.begin() + static_cast<long>(last));
    *version = history_.front().version;
    return *history_.front().corrections;
  }
  // C(keyframe) from the newest corrections: that of the newest keyframe at or before it;
  // identity before any.
  SE3 Correction(int keyframe) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return corrections_ ? Lookup(*corrections_, keyframe) : SE3();
  }
  int version() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return version_;
  }
  // The newest corrections.
  std::map<int, SE3> Snapshot(int* version = nullptr) const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (version) *version = version_;
    return corrections_ ? *corrections_ : std::map<int, SE3>();
  }
  // The same rule over a snapshot.
  static SE3 Lookup(const std::map<int, SE3>& corrections, int keyframe) {
    auto it = corrections.upper_bound(keyframe);
    if (it == corrections.begin()) return SE3();
    return std::prev(it)->second;
  }

 private:
  struct Published {
    int keyframe;  // published while this (1-based) keyframe was processed
    int version;
    std::shared_ptr<const std::map<int, SE3>> corrections;
  };
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::shared_ptr<const std::map<int, SE3>> corrections_;
  int version_ = 0;
  int processed_ = 0;
  bool closed_ = false;
  bool record_history_ = false;
  std::vector<Published> history_;  // since the last AtProcessed answer
};

}  // namespace gf
