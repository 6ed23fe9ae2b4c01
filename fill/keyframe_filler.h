// The stereo fill of a stream of keyframes, as the pipeline's fill stage and `bench` both run it:
// each keyframe is paired (KeyframePairScheduler: a partner and a third view among the keyframes
// around it), its holes are filled by stereo (FillHolesByStereo), and the validated fills of the
// last keyframes are carried into it (FillCarrier). A keyframe's result comes out once `lookahead`
// later keyframes have arrived, or at Flush().
//
// Failures are contained per keyframe: one whose features, pairing, stereo or carry throws comes
// out with `record.failure` set and its sensor depth alone, and the stream goes on.
//
// No threads, no I/O. Usage:
//   gf::KeyframeFiller filler(camera, {});
//   for (each keyframe) for (const gf::FilledKeyframe& k : filler.Add(frame, world_from_camera))
//     write(k.key->frame, k.fill);         // k.fill.filled_depth: sensor depth + fills
//   for (const gf::FilledKeyframe& k : filler.Flush()) ...
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"
#include "fill/fill_carry.h"
#include "fill/keyframe_pairs.h"
#include "fill/stereo_fill.h"

namespace gf {

struct KeyframeFillerOptions {
  PairSelectionOptions pairs;
  StereoFillOptions stereo;
  FillCarryOptions carry;
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

// One keyframe's outcome, as report.json lists it.
struct KeyframeFill {
  std::string timestamp;       // KeyframeName
  std::string partner;         // partner's name, empty when none
  std::string third;           // the third view's name, empty when none
  std::string method;          // StereoFillResult::method: "rectified SGBM", "plane sweep", ...
  std::string path;            // StereoFillResult::path: how the pair was served
  std::string sgbm_refused;    // why a sideways pair did not get SGBM (degenerate rectification)
  bool sgbm_rescaled = false;  // its rectified focal length was reduced to fit the search
  bool sgbm_vertical = false;  // its baseline is mostly vertical: SGBM ran on transposed images
  std::string termination;
  std::string failure;  // non-empty: the keyframe was skipped, and why
  double baseline_m = 0;
  int matches = 0;
  bool third_view = false;
  int hole_pixels = 0;
  int filled_pixels = 0;             // own stereo and carried
  int carried_pixels = 0;            // holes filled from earlier keyframes' fills
  int corrected_pixels = 0;          // own fills the earlier keyframes' consensus replaced
  int witnesses = 0;                 // views that only witnessed the fill (max_witnesses)
  int corroborated_pixels = 0;       // own fills a view outside their pair corroborated
  int seen_through_pixels = 0;       // stereo fills dropped: another keyframe's sensor saw past
  double stereo_error_median_m = 0;  // stereo vs sensor on pixels both have
  double ms = 0;                     // stereo, validation and carry, milliseconds
};

struct FilledKeyframe {
  std::shared_ptr<const StereoKeyframe> key;      // the keyframe (frame, pose, features)
  std::shared_ptr<const StereoKeyframe> partner;  // null when unpaired or failed
  KeyframeFill record;
  StereoFillResult stereo;  // its own stereo (empty when unpaired or failed)
  CarriedFillResult fill;   // what to write: sensor depth, own and carried fills
  double stereo_ms = 0, carry_ms = 0;
};

// A keyframe between the steps of KeyframeFiller::Add(), for callers that run them on threads
// of their own.
struct FillTask {
  StereoJob job;          // Pair()'s
  FilledKeyframe result;  // Stereo() sets key, partner, record and stereo; Carry() the rest
  bool failed = false;    // `result` is final (Failed): the later steps pass it on
};

class KeyframeFiller {
 public:
  // Throws std::logic_error when options.Check() fails.
  KeyframeFiller(const Camera& camera, const KeyframeFillerOptions& options);
  // Adds a keyframe; returns the keyframes whose fill became ready (at most one, or the added
  // one itself when its features cannot be computed).
  std::vector<FilledKeyframe> Add(const RgbdFrame& frame, const SE3& world_from_camera);
  // End of the stream: the keyframes still waiting for later ones; `stop` (may be empty) is asked
  // between keyframes and ends the flush early when it returns true.
  std::vector<FilledKeyframe> Flush(const std::function<bool()>& stop = {});
  // Milliseconds the last Add() spent on features and pairing (pose refinement included).
  double last_pairing_ms() const { return last_pairing_ms_; }

  // Add() and Flush() in three steps: Pair() (or PairRest(), at the end), Stereo(), Carry(), each
  // step taking the tasks in the order the one before gave them. The steps use different parts
  // of the filler, so that three threads may run them at once (one thread per step); Stereo()
  // reads only the options.
  std::vector<FillTask> Pair(const RgbdFrame& frame, const SE3& world_from_camera);
  std::vector<FillTask> PairRest();
  void Stereo(FillTask* task) const;
  FilledKeyframe Carry(FillTask task);

 private:
  static FilledKeyframe Failed(std::shared_ptr<const StereoKeyframe> key,
                               const std::string& reason);

  Camera camera_;
  KeyframeFillerOptions options_;
  KeyframePairScheduler scheduler_;
  FillCarrier carrier_;
  double last_pairing_ms_ = 0;
};

}  // namespace gf
