// The fusion stage of the reconstruction: every tracked frame's depth and every keyframe's stereo
// fill fused into surfel maps (surfels/fusion.h) in its own thread.
//
// The track stage offers each tracked frame (with its pose and keyframe); the fill stage offers
// each keyframe's own stereo fill as it is written (the carried fills are the fills of earlier
// keyframes, which the map already fuses from those keyframes). Items queue in the order they
// arrive; for recorded input the producers wait for room, for live input a full queue drops the
// item (counted). The stage keeps one map per variant: a run keeps one ("with fill", or the
// sensor alone with --no-fill); `compare` keeps two, the same frames fused with and without the
// fills. Finish() drains the queue, joins the thread and writes each variant's map.ply through its
// sink; Report() gives report.json's "surfels" object for a variant.
//
// With loop closure, frames arrive with their tracked poses and keyframes; the stage fuses each
// at its keyframe's current correction (pose_corrections.h), and when new corrections are
// published it first moves every surfel with the keyframe it belongs to (ElasticFusion deforms
// its map; here the map is rigid per keyframe, which is what the pose graph corrects).
//
// Failures are contained per item: a frame or fill whose fusion throws is skipped, counted and
// logged; the run goes on.
//
// Thread-safety: Offer*() from the track and fill threads; Cancel() from any thread; Finish() and
// Report() from the owner's.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"
#include "pipeline/bounded_queue.h"
#include "pipeline/pose_corrections.h"
#include "pipeline/run_sink.h"
#include "pipeline/stage_thread.h"
#include "sfm/keyframe_filler.h"
#include "surfels/fusion.h"

namespace gf {

struct FusionStageOptions {
  FusionOptions fusion;
  int queue_capacity = 32;     // items (frames and fills) waiting for the worker
  int count_every = 10;        // surfel counts are recorded every this many frames
  bool fuse_carried = false;   // fuse the carried fills too (they repeat earlier keyframes')
  bool drop_when_busy = true;  // live input; recorded input waits (set by the pipeline)
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
  bool Check(std::string* message = nullptr) const;
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
              std::vector<Variant> variants, const PoseCorrections* corrections = nullptr);
  ~FusionStage();  // cancels and joins if Finish() was not called
  FusionStage(const FusionStage&) = delete;
  FusionStage& operator=(const FusionStage&) = delete;

  void OfferFrame(const RgbdFrame& frame, const SE3& world_from_camera, int keyframe);
  void OfferFill(const FilledKeyframe& filled, int keyframe);
  // Fuses what is queued, joins the worker, writes the maps. Rethrows a map that could not be
  // written. `poll` (may be empty) is called every 50 ms while it waits; true cancels the rest.
  void Finish(const std::function<bool()>& poll = {});
  void Cancel();
  int frames_fused() const { return frames_fused_; }
  // The model's depth at the pose of the frames_fused()-th frame, once at least `frames` frames
  // are fused (waits up to `timeout`); false when none is ready in time or the stage stopped.
  bool Prediction(int frames, std::chrono::milliseconds timeout, cv::Mat* depth,
                  SE3* world_from_camera);
  // report.json's "surfels" for variant `index`.
  nlohmann::ordered_json Report(size_t index = 0) const;
  // After Finish(): the first variant's model seen from world_from_camera (at the final
  // corrections) where its nearest stable surfel is a fill, gaps between the fill discs closed
  // (completion_max_gap_px); CV_32F metres, 0 elsewhere.
  cv::Mat RenderFills(const SE3& world_from_camera);

 private:
  struct Item {
    bool fill = false;
    RgbdFrame frame;
    SE3 world_from_camera;
    int keyframe = 0;
    cv::Mat filled_depth, fill_mask, confidence;  // fills only
  };
  struct Map {
    Variant variant;
    SurfelFusion fusion;
    std::vector<nlohmann::ordered_json> over_time;  // counts every count_every frames
    std::vector<double> frame_ms, fill_ms;
    int failed = 0;
    long redundant = 0, over_budget = 0;  // surfels merged as copies, removed over the budget
  };
  void Offer(Item item);
  void Run();
  void Fuse(const Item& item, const SE3& world_from_camera, Map* map);
  // Moves the maps by what the corrections changed since they were last applied.
  void ApplyCorrections();
  void Record(Map* map) const;

  Camera camera_;
  FusionStageOptions options_;
  std::vector<Map> maps_;
  BoundedQueue<Item> queue_;
  std::atomic<int> frames_fused_{0};
  std::atomic<int> dropped_{0};
  std::atomic<bool> cancelled_{false};
  std::mutex prediction_mutex_;
  std::condition_variable prediction_ready_;
  int prediction_frames_ = 0;
  bool prediction_closed_ = false;
  cv::Mat prediction_depth_;
  SE3 prediction_pose_;
  const PoseCorrections* corrections_;
  std::map<int, SE3> applied_;  // corrections the maps are at (worker thread)
  int applied_version_ = 0;
  int newest_keyframe_ = -1;  // of the items fused so far
  int corrections_applied_ = 0;
  StageThread worker_;
};

// report.json's "surfels" object of a fusion: stable count (the surfels map.ply holds), the
// counts by source, their area, and how they grew.
nlohmann::ordered_json SurfelReport(const SurfelFusion& fusion,
                                    const std::vector<nlohmann::ordered_json>& over_time);

}  // namespace gf
