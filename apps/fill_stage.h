// The asynchronous stereo-fill stage of `reconstruct`.
//
// The tracker hands every new keyframe to Offer(): keyframes go into a bounded queue; for live
// input a keyframe that finds the queue full is dropped from the fill (and counted), so tracking
// never waits on stereo; for recorded input Offer() waits for room (options.drop_when_busy). One
// worker thread pairs keyframes (KeyframePairScheduler), fills each keyframe's holes
// (FillHolesByStereo, with the third view when the pair selection found one) and writes, for every
// keyframe, after carrying the validated fills of the last few keyframes into its holes
// (CarryFills, sfm/fill_carry.h), in <out_dir>/keyframes/ (names in DESIGN.md):
//   <ts>.hole_mask.png     8-bit HoleCode (0 valid, 1 no return, 2 out of range, 3 shadow)
//   <ts>.depth_filled.png  16-bit millimetres: sensor depth plus filled pixels, 0 still empty
//   <ts>.fill_overlay.png  colour image, filled pixels green (cyan: carried from earlier
//                          keyframes; brighter = more confident), holes still empty magenta
//   <ts>.color.png         the keyframe's colour image (lossless; colmap-export uses it)
// Each file is written atomically. Finish() drains the queue and joins the worker; Report() then
// gives report.json's "fill" object.
//
// Failures are contained per keyframe: a keyframe whose features, pairing, stereo or carry throws
// is skipped with a warning naming it and the reason (its files then hold the sensor's depth
// alone), listed in the report's "failed_keyframes", and the stage goes on. Only a file that
// cannot be written stops the stage (Finish() rethrows it). Cancel() stops it early: what is
// queued is left unfilled and counted.
//
// Thread-safety: Offer() from one producer thread; Cancel() from any thread; Finish() and
// Report() from the producer's thread.
#pragma once

#include <atomic>
#include <exception>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"
#include "apps/bounded_queue.h"
#include "sfm/fill_carry.h"
#include "sfm/keyframe_pairs.h"
#include "sfm/stereo_fill.h"

namespace gf {

struct FillStageOptions {
  PairSelectionOptions pairs;
  StereoFillOptions stereo;
  FillCarryOptions carry;
  int queue_capacity = 16;  // keyframes waiting for the worker
  // Live input: a keyframe arriving at a full queue is dropped from the fill (and counted), so
  // tracking never waits. Recorded input (false): Offer() waits for room instead, so that every
  // keyframe is filled; nothing is lost by waiting on a file.
  bool drop_when_busy = true;
  bool Check(std::string* message = nullptr) const;
};

// One keyframe's outcome, as report.json lists it.
struct KeyframeFill {
  std::string timestamp;
  std::string partner;  // partner's timestamp, empty when none
  std::string third;    // the third view's timestamp, empty when none
  std::string method;   // StereoFillResult::method: "rectified SGBM", "plane sweep", ...
  std::string termination;
  double baseline_m = 0;
  int matches = 0;
  bool third_view = false;
  std::string path;            // StereoFillResult::path: how the pair was served
  std::string sgbm_refused;    // why a sideways pair did not get SGBM (degenerate rectification)
  bool sgbm_rescaled = false;  // its rectified focal length was reduced to fit the search
  std::string failure;         // non-empty: the keyframe was skipped, and why
  int hole_pixels = 0;
  int filled_pixels = 0;             // own stereo and carried
  int carried_pixels = 0;            // holes filled from earlier keyframes' fills
  int corrected_pixels = 0;          // own fills the earlier keyframes' consensus replaced
  double stereo_error_median_m = 0;  // stereo vs sensor on pixels both have
  double ms = 0;                     // pairing + stereo + validation, milliseconds
};

class FillStage {
 public:
  FillStage(const Camera& camera, const FillStageOptions& options, const std::string& out_dir);
  ~FillStage();  // joins the worker (dropping what is queued) if Finish() was not called
  FillStage(const FillStage&) = delete;
  FillStage& operator=(const FillStage&) = delete;

  // False when the keyframe was dropped (queue full and drop_when_busy, or the stage stopped).
  bool Offer(const RgbdFrame& frame, const SE3& world_from_camera);
  // Processes what is queued, pairs the last keyframes, joins the worker. Rethrows a worker error
  // (an output file that could not be written). While it waits, a `cancel` that returns true
  // (polled every 50 ms) cancels the rest.
  void Finish(const std::function<bool()>& cancel = {});
  // Stops early: the keyframe in progress is finished, the queued ones are not filled.
  void Cancel();
  nlohmann::ordered_json Report() const;
  const std::vector<KeyframeFill>& keyframes() const { return done_; }

 private:
  struct Offered {
    RgbdFrame frame;
    SE3 world_from_camera;
  };
  void Run();
  void Process(const StereoJob& job);
  // The keyframe's stereo fill and carried fills (throws on failure).
  CarriedFillResult Fill(const StereoJob& job, KeyframeFill* k);
  void Write(const RgbdFrame& key1, const CarriedFillResult& c) const;
  void Skip(const RgbdFrame& key1, const std::string& reason);

  Camera camera_;
  FillStageOptions options_;
  std::string keyframe_dir_;
  BoundedQueue<Offered> queue_;
  std::vector<KeyframeFill> done_;  // written by the worker, read after Finish()
  FillCarrier carrier_;             // the last keyframes' own fills (worker only)
  int dropped_ = 0;                 // live input: keyframes that found the queue full
  int accepted_ = 0;                // keyframes Offer() queued (producer's count)
  int not_filled_ = 0;              // offered after the stage stopped (producer's count)
  std::atomic<bool> cancelled_{false};
  std::atomic<bool> stopped_{false};  // the worker ended (error or Cancel())
  std::exception_ptr error_;
  std::thread worker_;
};

}  // namespace gf
