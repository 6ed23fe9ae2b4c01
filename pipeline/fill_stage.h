// The stereo-fill stage of the reconstruction: fills every keyframe's depth holes in its own
// thread while tracking goes on.
//
// The tracker hands each new keyframe to Offer(): keyframes go into a bounded queue; for live
// input a keyframe that finds the queue full is dropped from the fill (and counted), so tracking
// never waits on stereo; for recorded input Offer() waits for room (options.drop_when_busy). Three
// threads run the KeyframeFiller's steps (fill/keyframe_filler.h), joined by small bounded queues,
// so that one keyframe's stereo overlaps the next one's pairing and the last one's writing:
// gf-fill pairs (features, partner, refined poses), gf-stereo fills the holes by stereo,
// gf-fill-write carries the earlier fills into each keyframe, writes its images through the
// RunSink (run_sink.h) and hands its fill to the fusion stage, saying after each keyframe offered
// that it is processed (the fusion stage joins fills to the map at fixed points of the sequence:
// fusion_stage.h). Each step takes the keyframes in order, so that the outputs do not depend on
// the threads' timing.
//
// Failures are contained per keyframe: one whose features, pairing, stereo or carry throws is
// skipped with a warning naming it and the reason (its files hold the sensor's depth alone),
// listed in Report()'s "failed_keyframes", and the stage goes on. Only a keyframe that cannot be
// written stops the stage (Finish() rethrows it). Cancel() stops it early: what is queued is left
// unfilled and counted.
//
// Thread-safety: Offer() from one producer thread; Cancel() and progress() from any thread;
// Finish() and Report() from the owner's.
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"
#include "pipeline/bounded_queue.h"
#include "pipeline/fusion_stage.h"
#include "pipeline/run_sink.h"
#include "pipeline/stage_reports.h"
#include "pipeline/stage_thread.h"
#include "fill/keyframe_filler.h"

namespace gf {

struct FillStageOptions {
  PairGeometryOptions geometry;  // for pair selection and stereo alike (their own copies are set
                                 // from this one)
  PairSelectionOptions pairs;
  StereoFillOptions stereo;
  FillCarryOptions carry;
  int queue_capacity = 16;  // keyframes waiting for the worker
  // Live input: a keyframe arriving at a full queue is dropped from the fill (and counted), so
  // tracking never waits. Recorded input (false): Offer() waits for room instead, so that every
  // keyframe is filled; nothing is lost by waiting on a file.
  bool drop_when_busy = true;
  KeyframeFillerOptions Filler() const;
  bool Check(std::string* message = nullptr) const;
};

class FillStage {
 public:
  // `sink` and `fusion` (may be null: no map) must outlive the stage; each filled keyframe goes to
  // the fusion stage after it is written.
  FillStage(const Camera& camera, const FillStageOptions& options, RunSink* sink,
            FusionStage* fusion = nullptr);
  ~FillStage();  // cancels and joins if Finish() was not called
  FillStage(const FillStage&) = delete;
  FillStage& operator=(const FillStage&) = delete;

  // False when the keyframe was dropped (queue full and drop_when_busy, or the stage stopped).
  // `keyframe` is the tracker's number for it (what the fusion stage corrects poses by).
  // measured_depth: when frame.depth was moved to the stamp's instant (the rolling-shutter model),
  // the depth as the sensor gave it. The stereo fills the moved frame, whose depth agrees with the
  // pose; the written keyframe keeps the sensor's pixels as measured (empty: frame.depth is).
  bool Offer(const RgbdFrame& frame, const SE3& world_from_camera, int keyframe = -1,
             const cv::Mat& measured_depth = cv::Mat());
  // Processes what is queued, pairs the last keyframes, joins the worker. Rethrows a worker error
  // (a keyframe that could not be written). While it waits, `poll` (may be empty) is called
  // every 50 ms; when it returns true the rest is cancelled.
  void Finish(const std::function<bool()>& poll = {});
  // Stops early: the keyframe in progress is finished, the queued ones are not filled.
  void Cancel();
  // Keyframes offered and keyframes done so far (any thread).
  int offered() const { return accepted_; }
  int done() const { return done_count_; }
  FillReport Report() const;  // report.json's "fill"
  std::vector<KeyframeFill> keyframes() const;

  // CPU seconds the stage's own threads used, once they have ended.
  double cpu_seconds() const {
    return worker_.cpu_seconds() + stereo_worker_.cpu_seconds() + writer_.cpu_seconds();
  }

 private:
  struct Offered {
    RgbdFrame frame;
    SE3 world_from_camera;
    int keyframe = -1;
    cv::Mat measured_depth;  // empty: frame.depth is as measured
  };
  // Keyframes between the threads; after them, the fills of the first `processed` keyframes
  // offered are all out (0: not a point to say so).
  struct Batch {
    std::vector<FillTask> tasks;
    int processed = 0;
  };
  void RunPairing(KeyframeFiller* filler);
  void RunStereo(const KeyframeFiller* filler);
  void RunWriting(KeyframeFiller* filler);
  // A thread that ends with an error stops the others (and Offer()).
  void CloseQueues();
  // Ends a thread's output: closes `out` when the thread finished (ok), every queue otherwise.
  struct EndOfBatches {
    FillStage* stage;
    BoundedQueue<Batch>* out;
    bool ok = false;
    ~EndOfBatches() { ok ? out->Close() : stage->CloseQueues(); }
  };
  void Write(const FilledKeyframe& k);

  Camera camera_;
  FillStageOptions options_;
  RunSink* sink_;
  FusionStage* fusion_;
  BoundedQueue<Offered> queue_;
  BoundedQueue<Batch> paired_{2}, stereo_done_{2};
  std::unique_ptr<KeyframeFiller> filler_;
  std::mutex order_mutex_;  // keyframe_of_ and measured_of_ (gf-fill adds, gf-fill-write reads)
  std::vector<int> keyframe_of_;  // the filler's keyframe ids (arrival order) -> the tracker's
  std::map<int, cv::Mat> measured_of_;  // frame index -> measured depth, until it is written
  mutable std::mutex done_mutex_;
  std::vector<KeyframeFill> done_;  // written by the worker
  std::atomic<int> done_count_{0};
  std::atomic<int> accepted_{0};  // keyframes Offer() queued
  int dropped_ = 0;               // live input: keyframes that found the queue full (producer)
  int not_filled_ = 0;            // offered after the stage stopped (producer)
  std::atomic<bool> cancelled_{false};
  std::atomic<bool> stopped_{false};  // the worker ended (error or Cancel())
  StageThread worker_, stereo_worker_, writer_;
};

}  // namespace gf
