// The loop-closure stage of the reconstruction, in its own thread: every keyframe the tracker
// makes joins a keyframe database and a pose graph; loops found and verified against earlier
// keyframes (registration/loop_detector.h) become graph edges; after each keyframe that adds
// loops the graph is optimised (registration/pose_graph.h) and the corrections published
// (pose_corrections.h), which the fusion stage applies to the map and the run to its trajectory.
//
// Keyframes reach it through a bounded queue: for recorded input the tracker waits for room (so
// that no keyframe is lost), for live input a full queue drops the keyframe (counted; the graph
// then links the next one to the last it has by a weak edge). It is also the tracker's Relocaliser:
// a lost frame is looked up in the same database, from the tracking thread.
//
// Failures are contained per keyframe: one whose loop search throws is logged and counted, and the
// run goes on. Finish() drains the queue, optimises once more and publishes. After each keyframe
// it marks the corrections processed (PoseCorrections::MarkProcessed), so that the fusion stage
// applies them at fixed points of the sequence; for recorded input a relocalisation first waits
// for every keyframe offered before it, so that it searches the same database every run.
//
// Thread-safety: Offer() from the tracking thread; Relocalise() from the tracking thread;
// Cancel() from any thread; Finish() and Report() from the owner's.
#pragma once

#include <atomic>
#include <functional>
#include <set>
#include <shared_mutex>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "pipeline/bounded_queue.h"
#include "pipeline/pose_corrections.h"
#include "pipeline/stage_reports.h"
#include "pipeline/stage_thread.h"
#include "registration/keyframe_database.h"
#include "registration/loop_detector.h"
#include "registration/pose_graph.h"
#include "registration/tracker.h"

namespace gf {

struct LoopStageOptions {
  KeyframeDatabaseOptions database;
  LoopDetectorOptions detector;
  PoseGraphOptions graph;
  int queue_capacity = 16;  // keyframes waiting for the loop search
  // Errors tracking's alignment information leaves out, added to its covariance for the odometry
  // edges (as detector.verification.noise is for loops; pose_graph.h).
  AlignmentNoise odometry_noise;
  // A tracking restart links the new keyframe to the last good pose with this uncertainty.
  double gap_sigma_m = 0.5;
  double gap_sigma_deg = 30.0;
  int relocalise_candidates = 3;  // best appearance matches verified per lost frame
  bool drop_when_busy = true;     // live input; recorded input waits (set by the pipeline)
  // A place already stored (set by the pipeline from the tracker's keyframe policy; not a setting
  // of its own): a keyframe that a verified loop puts within this rotation and translation of a
  // stored keyframe is one the tracker would not have made there. It stays in the pose graph, but
  // its features and depth are not kept, so the database grows with the places a capture visits,
  // not with its length.
  KeyframePolicy same_place;
  // After an optimisation, a keyframe that a verified loop ties to another and that is more than
  // this many keyframes older than the newest is held at its optimised pose: its place is
  // settled, and later loops move only the newer keyframes and those no loop has tied yet. An
  // optimisation then costs about the same however long the capture (a loop over a long stretch
  // without loops still moves that whole stretch).
  int free_keyframes = 50;
  bool Check(std::string* message = nullptr) const;
};

// A keyframe as the tracker hands it over, with how it follows from the keyframes before it.
struct LoopKeyframeItem {
  enum class Link {
    kFirst,        // the first keyframe: the world frame
    kOdometry,     // tracked from keyframe `linked_to`
    kRelocalised,  // found again against keyframe `linked_to` after a loss
    kRestarted,    // tracking restarted at keyframe `linked_to`'s last good pose (a guess)
  };
  int id = 0;             // the tracker's keyframe number
  RgbdFrame frame;        // with the depth tracking used (undistorted, on the stage's camera)
  SE3 world_from_camera;  // as tracked
  std::shared_ptr<const FrameFeatures> features;
  Link link = Link::kFirst;
  int linked_to = -1;
  SE3 linked_from_this;                     // the measured relative pose
  Matrix6d information = Matrix6d::Zero();  // of that measurement, as the alignment gave it
};

class LoopClosureStage : public Relocaliser {
 public:
  // `camera`: the one tracking works on (the input's without distortion). `corrections` must
  // outlive the stage.
  LoopClosureStage(const Camera& camera, const LoopStageOptions& options,
                   PoseCorrections* corrections);
  ~LoopClosureStage() override;  // cancels and joins if Finish() was not called
  LoopClosureStage(const LoopClosureStage&) = delete;
  LoopClosureStage& operator=(const LoopClosureStage&) = delete;

  // False when the keyframe was dropped (queue full and drop_when_busy, or the stage stopped).
  bool Offer(LoopKeyframeItem item);
  // Relocaliser: the best appearance matches among the keyframes searched so far.
  std::optional<Relocalisation> Relocalise(const RgbdFrame& frame,
                                           const FrameFeatures& features) override;
  // Searches what is queued, optimises, publishes, joins. `poll` (may be empty) is called every
  // 50 ms while it waits; true cancels the rest.
  void Finish(const std::function<bool()>& poll = {});
  void Cancel();
  int keyframes_done() const { return keyframes_done_; }
  // report.json's "loops".
  LoopReport Report() const;

  // CPU seconds the stage's own thread used, once it has ended.
  double cpu_seconds() const { return worker_.cpu_seconds(); }

 private:
  void Run();
  void Process(const LoopKeyframeItem& item);
  // Adds the keyframe's node and its link to the graph; returns the node's initial estimate.
  SE3 AddNode(const LoopKeyframeItem& item, double scene_depth_m);
  void Optimise();
  void Record(const LoopKeyframeItem& item, const LoopDetection& detection);

  Camera camera_;
  LoopStageOptions options_;
  PoseCorrections* corrections_;
  BoundedQueue<LoopKeyframeItem> queue_;
  // The database is read by the loop thread and by relocalisation (tracking thread), written by
  // the loop thread.
  mutable std::shared_mutex database_mutex_;
  KeyframeDatabase database_;
  // Loop thread only, then the owner's after Finish().
  LoopDetector detector_;
  PoseGraph graph_;
  std::map<int, SE3> tracked_;  // world_from_keyframe as tracked, by id
  std::set<int> tied_;          // keyframes a loop edge ties, not yet held
  int last_id_ = -1;
  bool unoptimised_loops_ = false;
  std::vector<AcceptedLoop> accepted_;  // the first ones, for the report
  std::map<std::string, int> refused_;  // reasons, without their figures
  int candidates_ = 0, verified_ = 0, pending_ = 0, optimisations_ = 0, failed_ = 0;
  int same_place_ = 0;  // keyframes not stored: their place was (same_place)
  std::vector<double> keyframe_ms_, optimise_ms_;
  std::atomic<int> keyframes_done_{0};
  int offered_ = 0;  // keyframes queued (tracking thread)
  std::atomic<int> dropped_{0};
  std::atomic<int> relocalisation_attempts_{0}, relocalised_{0};
  std::atomic<bool> cancelled_{false};
  StageThread worker_;
};

}  // namespace gf
