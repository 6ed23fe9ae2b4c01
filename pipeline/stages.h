// The read and track stages of the reconstruction, each in its own thread, joined by a bounded
// queue of frames (a fast source blocks instead of exhausting memory); the track stage hands new
// keyframes to the fill stage (fill_stage.h).
//
// ReadStage decodes frames [first_frame, end_frame) of a FrameSource into the queue; a frame that
// cannot be read travels down the queue as an error, so the frames before it are tracked first
// and the error then ends tracking. TrackStage tracks every frame (frame-to-keyframe ICP,
// registration/tracker.h), checks the first frames' depth scale (DepthScaleProblem), keeps the
// trajectory as tracked with each frame's keyframe (lost frames have none), and hands frames to
// the fusion stage and keyframes to the fill and loop-closure stages (which is also the tracker's
// relocaliser). Stop() ends either stage at the next frame.
//
// Thread-safety: Stop() and the counters from any thread; the results once the stage has ended.
#pragma once

#include <atomic>
#include <exception>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/frame_source.h"
#include "acquisition/trajectory.h"
#include "pipeline/bounded_queue.h"
#include "pipeline/fill_stage.h"
#include "pipeline/fusion_stage.h"
#include "pipeline/loop_stage.h"
#include "pipeline/stage_thread.h"
#include "registration/tracker.h"

namespace gf {

struct FrameItem {
  RgbdFrame frame;
  double read_ms = 0;
  std::exception_ptr error;  // the frame could not be read: this ends the stream
};

class ReadStage {
 public:
  // `source` and `queue` must outlive the stage; end_frame < 0 reads to the end.
  ReadStage(FrameSource* source, int first_frame, int end_frame, BoundedQueue<FrameItem>* queue);
  ~ReadStage();
  void Stop();
  void Join() { thread_.Join(); }

  // CPU seconds the stage's own thread used, once it has ended.
  double cpu_seconds() const { return thread_.cpu_seconds(); }

 private:
  void Run();
  FrameSource* source_;
  int first_frame_, end_frame_;
  BoundedQueue<FrameItem>* queue_;
  std::atomic<bool> stop_{false};
  StageThread thread_;
};

// What tracking did, for the report.
struct TrackingRecord {
  Trajectory trajectory;           // the frames with a pose, as tracked
  std::vector<int> keyframe;       // per trajectory entry: the keyframe it was tracked against
  std::vector<std::string> names;  // ... and its frame's KeyframeName
  std::vector<std::string> lost_frames;  // names of the frames without a pose
  int relocalised = 0, restarted = 0;
  std::vector<double> read_ms, track_ms;
  int frames = 0, lost = 0, keyframes = 0;
  std::vector<double> median_depths;  // of the first frames with returns, metres
};

class TrackStage {
 public:
  // `queue`, `fill`, `fusion` and `loop` (each may be null: no fill, no map, no loop closure)
  // must outlive the stage.
  // camera_file is the file an implausible depth scale is blamed on (the camera.json in use).
  // With frame_to_model, each frame is first tracked as usual, then refined against the fusion
  // stage's model of the frames before it (FrameToKeyframeTracker::SetModelReference).
  TrackStage(const FrameSource& source, const TrackerOptions& options,
             const std::string& camera_file, BoundedQueue<FrameItem>* queue, FillStage* fill,
             FusionStage* fusion, LoopClosureStage* loop, bool frame_to_model = false);
  ~TrackStage();
  void Stop();
  // True once tracking has ended (waits at most `timeout`).
  bool WaitFor(std::chrono::milliseconds timeout) { return thread_.WaitFor(timeout); }
  void Join() { thread_.Join(); }
  // What ended tracking early (a frame that could not be read, an implausible depth scale, a
  // keyframe without colour for the fill); null when it ran to the end or was stopped.
  std::exception_ptr error() const { return thread_.error(); }
  int frames() const { return frames_; }
  // Once ended.
  const TrackingRecord& record() const { return record_; }

  // CPU seconds the stage's own thread used, once it has ended.
  double cpu_seconds() const { return thread_.cpu_seconds(); }

 private:
  void Run();
  void Track(const RgbdFrame& frame, FrameToKeyframeTracker* tracker);
  // frame: as measured; placed: its depth moved to the stamp's instant (the same frame where
  // tracking did not model the rolling shutter).
  void OfferKeyframe(const RgbdFrame& frame, const RgbdFrame& placed, const TrackingResult& r,
                     int keyframe);
  void CheckDepthScale(const RgbdFrame& frame);

  const FrameSource& source_;
  TrackerOptions options_;
  std::string camera_file_;
  BoundedQueue<FrameItem>* queue_;
  FillStage* fill_;
  FusionStage* fusion_;
  LoopClosureStage* loop_;
  bool frame_to_model_;
  int last_keyframe_ = -1;  // the newest keyframe handed to loop closure
  SE3 last_keyframe_pose_;  // ... its tracked pose
  std::atomic<bool> stop_{false};
  std::atomic<int> frames_{0};
  int offered_to_fusion_ = 0;  // frames handed to the fusion stage
  SequencePoint handed_;       // keyframes handed to the fill and loop stages so far
  TrackingRecord record_;
  StageThread thread_;
};

}  // namespace gf
