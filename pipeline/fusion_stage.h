// The fusion stage of the reconstruction: every tracked frame's depth and every keyframe's stereo
// fill fused into surfel maps (surfels/fusion.h) in its own thread.
//
// The track stage offers each tracked frame (with its pose and keyframe) into a bounded queue: for
// recorded input it waits for room, for live input a full queue drops the frame (counted). The
// fill stage offers each keyframe's own stereo fill as it is written (the carried fills are the
// fills of earlier keyframes, which the map already fuses from those keyframes). The stage keeps
// one map per variant: a run keeps one ("with fill", or the sensor alone with --no-fill);
// `compare` keeps two, the same frames fused with and without the fills. Finish() drains the
// queue, joins the thread and writes each variant's map.ply through its sink; Report() gives
// report.json's "surfels" object for a variant.
//
// With loop closure, frames arrive with their tracked poses and keyframes; the stage fuses each
// at its keyframe's correction (pose_corrections.h), and when the corrections change it first
// moves every surfel with the keyframe it belongs to (ElasticFusion deforms its map; here the map
// is rigid per keyframe, which is what the pose graph corrects).
//
// Reproducible (recorded input): what joins the map, and when, is fixed by the frame sequence,
// never by which thread finishes first. Each frame carries a SequencePoint: the keyframes the
// fill and loop stages must have processed before it is fused. The stage waits for them, then
// fuses the fills those keyframes produced (in the order produced) and applies the corrections
// as they stood after them (PoseCorrections::AtProcessed); the fills produced at the end of the
// fill stage (its last keyframes) and the final corrections join after the last frame. Live
// input never waits: fills join when they arrive (at most queue_capacity wait; more are dropped,
// counted) and the newest corrections apply.
//
// Failures are contained per item: a frame or fill whose fusion throws is skipped, counted and
// logged; the run goes on.
//
// Thread-safety: OfferFrame() from the track thread; OfferFill(), FillsProcessed() and
// CloseFills() from the fill stage's writing thread; Cancel() from any thread; Finish() and
// Report() from the owner's.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"
#include "pipeline/bounded_queue.h"
#include "pipeline/pose_corrections.h"
#include "pipeline/run_sink.h"
#include "pipeline/stage_reports.h"
#include "pipeline/stage_thread.h"
#include "fill/keyframe_filler.h"
#include "surfels/fusion.h"

namespace gf {

struct FusionStageOptions {
  FusionOptions fusion;
  int queue_capacity = 32;     // items (frames and fills) waiting for the worker
  int count_every = 10;        // surfel counts are recorded every this many frames
  bool fuse_carried = false;   // fuse the carried fills too (they repeat earlier keyframes')
  // Live input (set by the pipeline): a full queue drops the item, and fills and corrections join
  // when they arrive. Recorded input (false): producers wait for room, and fills and corrections
  // join at the frames' SequencePoints.
  bool drop_when_busy = true;
  // After each frame, render the first variant's model at that frame's pose for frame-to-model
  // tracking (Prediction()).
  bool predict = false;
  // At the end of a run with the fill, each keyframe's holes that its own fill left empty take
  // the final model's depth where the model's nearest surfel there is a fill (RenderFills): fills
  // of other keyframes, confirmed across keyframes (FusionOptions), seen from this one.
  bool complete_keyframes = true;
  // Gaps between the rendered fill discs (RenderFills) of at most this many pixels are closed
  // where the discs on either side lie on one surface (depths within fusion.free_space_margin;
  // CloseSplatGaps): the renderer's discs, seen from a keyframe other than the ones that measured
  // them, do not tile the image. Pixels; 0 leaves the gaps.
  int completion_max_gap_px = 4;
  // A keyframe takes the map's depth only where the map's surface is confirmed from its side
  // (MapView, surfels/fusion.h). Each rule leaves out a class of pixels that the map fills more
  // often wrongly than rightly, on the tuning frames and on the check frames alike (punched TUM
  // head and mid, at 1-3 times the capture's speed: docs/experiments/
  // 2026-12-06-completion-that-knows.md). The nearest surfel's normal within this angle of the
  // direction back to the keyframe (degrees, at most 90): at 90, a surface seen from behind was
  // not measured from this side (those pixels were right 20-42% of the time); 75 also leaves out
  // surfaces seen nearly edge-on, right 33% of the time on head but 59% on mid: not adopted...
  double completion_max_angle_deg = 90;
  // ... the surface carries at least this support (MapView::support: the summed confidence of the
  // surfels whose discs the pixel's ray meets within fusion.free_space_margin of its depth, the
  // weight of the measurements that put a surface there; a sensor frame adds at most 1 to a
  // surfel, a fill pixel fusion.fill_weight times its stereo confidence). 0: any stable fill,
  // which a second keyframe or an independent view has already confirmed (FusionOptions); a
  // threshold of 10 left out pixels right about half the time, so the support goes into the
  // confidence instead...
  double completion_min_support = 0;
  // ... and no sensor pixel of the keyframe within this many pixels lies in front of it by more
  // than fusion.free_space_margin: the map's surface there is behind the object the keyframe saw
  // at the hole's rim (MapCompletion::occluder_px; 0: not checked; those pixels were right 46%
  // of the time).
  int completion_occluder_px = 5;
  // The completed pixels' confidence (written to fill_confidence.png): the facing cosine times
  // support / (support + completion_support_half), so half the facing's at this support.
  double completion_support_half = 10;
  bool Check(std::string* message = nullptr) const;
};

// How far the fill and loop-closure stages must have got before a frame joins the map (recorded
// input): the keyframes each had been handed when the frame was tracked, this frame's own
// keyframe included.
struct SequencePoint {
  int fills = 0;  // keyframes the fill stage must have processed: their fills join first
  int loops = 0;  // keyframes the loop stage must have processed: its corrections then apply
};

class FusionStage {
 public:
  struct Variant {
    std::string name;   // "with_fill", "without_fill"
    bool fills = true;  // fuse the keyframes' fills
    RunSink* sink;      // where its map.ply goes (must outlive the stage)
  };
  // `corrections` (may be null: poses as tracked) must outlive the stage.
  FusionStage(const Camera& camera, const FusionStageOptions& options,
              std::vector<Variant> variants, PoseCorrections* corrections = nullptr);
  ~FusionStage();  // cancels and joins if Finish() was not called
  FusionStage(const FusionStage&) = delete;
  FusionStage& operator=(const FusionStage&) = delete;

  void OfferFrame(const RgbdFrame& frame, const SE3& world_from_camera, int keyframe,
                  SequencePoint at = {});
  // A keyframe's fill, produced while the fill stage processes its (n + 1)-th keyframe, n being
  // the last FillsProcessed(n); it joins the map before the first frame whose at.fills > n.
  void OfferFill(const FilledKeyframe& filled, int keyframe);
  // The fill stage has processed its first n keyframes (n grows by one at a time).
  void FillsProcessed(int n);
  // The fill stage has ended (no more fills): frames stop waiting for it.
  void CloseFills();
  // Fuses what is queued, joins the worker, completes clear objects (surfels/revolution.h; `views`,
  // may be empty: colour views for their outlines, at the final corrections), writes the maps.
  // Rethrows a map that could not be written. `poll` (may be empty) is called every 50 ms while it
  // waits; true cancels the rest.
  void Finish(const std::function<bool()>& poll = {}, const OutlineViews& views = {});
  void Cancel();
  int frames_fused() const { return frames_fused_; }
  // The model's depth at the pose of the frames_fused()-th frame, once at least `frames` frames
  // are fused (waits up to `timeout` for live input; recorded input waits until they are);
  // false when none is ready in time or the stage stopped.
  bool Prediction(int frames, std::chrono::milliseconds timeout, cv::Mat* depth,
                  SE3* world_from_camera);
  // report.json's "surfels" for variant `index`.
  SurfelReport Report(size_t index = 0) const;
  // After Finish(): what the first variant's model offers a keyframe at world_from_camera (at the
  // final corrections): its depth where the nearest stable surfel is a fill, gaps between the
  // fill discs closed (completion_max_gap_px), kept where the surface is confirmed from that side
  // (completion_max_angle_deg, completion_min_support), with its confidence.
  // Several threads may call it at once once PrepareRenders() has run (the map no longer
  // changes after Finish()).
  MapCompletion RenderFills(const SE3& world_from_camera);
  void PrepareRenders();

  // CPU seconds the stage's own thread used, once it has ended.
  double cpu_seconds() const { return worker_.cpu_seconds(); }

 private:
  struct Item {
    bool fill = false;
    RgbdFrame frame;
    SE3 world_from_camera;
    int keyframe = 0;
    SequencePoint at;                             // frames only
    int produced_at = 0;                          // fills only: the fill stage's keyframe (1-based)
    cv::Mat filled_depth, fill_mask, confidence;  // fills only
  };
  struct Map {
    Variant variant;
    SurfelFusion fusion;
    std::vector<SurfelCountAt> over_time;  // counts every count_every frames
    std::vector<double> frame_ms, fill_ms;
    int failed_frames = 0, failed_fills = 0;
    std::string first_failure;  // what the first failed item threw
    long redundant = 0, over_budget = 0;  // surfels merged as copies, removed over the budget
    RevolutionResult revolutions;  // clear objects completed at the end (glass.revolution)
  };
  void Run();
  // Before a frame: the corrections and fills due at `at` (recorded input), or those that have
  // arrived (live).
  void CatchUp(const SequencePoint& at);
  // The fills produced up to the fill stage's keyframe n, in the order produced; with `wait`,
  // once the fill stage has processed n keyframes (or ended).
  std::vector<Item> TakeFills(int n, bool wait);
  // Fuses the item into every map at its keyframe's applied correction.
  void FuseItem(const Item& item);
  void Fuse(const Item& item, const SE3& world_from_camera, Map* map);
  // Moves the maps by what `latest` (of `version`) changes against the corrections applied.
  void ApplyCorrections(std::map<int, SE3> latest, int version);
  void Record(Map* map) const;

  Camera camera_;
  FusionStageOptions options_;
  std::vector<Map> maps_;
  BoundedQueue<Item> queue_;
  std::mutex fills_mutex_;  // the fills, from the fill thread
  std::condition_variable fills_changed_;
  std::deque<Item> fills_;  // in the order produced
  int fills_processed_ = 0;
  bool fills_closed_ = false;
  std::atomic<int> frames_fused_{0};
  std::atomic<int> dropped_{0};
  std::atomic<bool> cancelled_{false};
  std::mutex prediction_mutex_;
  std::condition_variable prediction_ready_;
  int prediction_frames_ = 0;
  bool prediction_closed_ = false;
  cv::Mat prediction_depth_;
  SE3 prediction_pose_;
  PoseCorrections* corrections_;  // read (AtProcessed forgets what it has answered)
  std::map<int, SE3> applied_;  // corrections the maps are at (worker thread)
  int applied_version_ = 0;
  int newest_keyframe_ = -1;  // of the items fused so far
  int corrections_applied_ = 0;
  StageThread worker_;
};

}  // namespace gf
