// What each stage of a run reports, as types: the fill stage's FillReport, the fusion stage's
// SurfelReport, the loop-closure stage's LoopReport, the map's completion of the keyframes
// (ModelCompletionReport) and the steps' times (StepTimes). The stages return these; the run reads
// their fields (Reconstruction::Summarise) and report.json holds them (pipeline/run_report.h),
// written and read back by the to_json and from_json functions of stage_reports.cc alone
// (nlohmann::json finds them by argument-dependent lookup: `json(report)` writes one,
// `j.get<FillReport>()` reads one; a key absent from an older report leaves its field's default).
// DESIGN.md names report.json's keys; they are the fields' names here.
#pragma once

#include <cstddef>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fill/keyframe_filler.h"

namespace gf {

// How long a stage's steps took: {"median_ms", "max_ms", "count"}, null times when none ran.
struct StepTimes {
  std::optional<double> median_ms, max_ms;
  size_t count = 0;
  static StepTimes Of(std::vector<double> ms);
};

// A keyframe the fill skipped, and why.
struct FailedKeyframe {
  std::string timestamp, reason;
};

// fill.model_completion: each filled keyframe's holes that its own fill left, completed from the
// final map's fills (pipeline/map_completion.h).
struct ModelCompletionReport {
  int keyframes = 0;        // keyframes that gained pixels
  long pixels = 0;          // hole pixels completed
  double seconds = 0;       // wall time of the completion
  bool stopped = false;     // a stop request ended it before every keyframe was done
  int keyframes_done = 0;   // keyframes completed (or found with nothing to complete)
  int keyframes_to_do = 0;  // keyframes the fill wrote
  int glass_keyframes = 0;  // keyframes that gained clear-glass pixels (transparent surfels)
  long glass_pixels = 0;    // of which pixels
};

// report.json's "fill": the fill stage's totals over its keyframes, and each keyframe's record.
struct FillReport {
  long hole_pixels = 0, filled_pixels = 0, carried_pixels = 0, corrected_pixels = 0,
       corroborated_pixels = 0, seen_through_pixels = 0;
  std::optional<double> stereo_error_median_m;  // median of the paired keyframes' (metres)
  int keyframes_filled = 0;                     // keyframes the stage finished (filled, or failed)
  int keyframes_paired = 0;                     // of which found a partner
  int keyframes_dropped = 0;                    // live input: found the queue full
  int keyframes_not_filled = 0;                 // queued or offered when the run stopped
  std::vector<FailedKeyframe> failed_keyframes;
  // How many pairs were served which way (StereoFillResult::path names, the usual ones first),
  // and why sideways pairs did not get SGBM.
  std::vector<std::pair<std::string, int>> pair_paths, sgbm_refused;
  int sgbm_rescaled = 0, sgbm_vertical = 0;
  std::optional<double> pair_median_ms, pair_max_ms;
  std::vector<KeyframeFill> per_keyframe;
  std::optional<ModelCompletionReport> model_completion;  // once the map has completed them

  double fill_rate() const { return hole_pixels ? double(filled_pixels) / hole_pixels : 0.0; }
  // The report of `keyframes` (as the stage recorded them), `dropped` and `not_filled` as above.
  static FillReport Of(const std::vector<KeyframeFill>& keyframes, int dropped, int not_filled);
};

// The stable surfels counted every few frames (report.json's surfels.count_over_time).
struct SurfelCountAt {
  long frame = 0, stable = 0, sensor = 0, stereo_fill = 0, unstable = 0;
};

// report.json's "surfels": a fusion variant's map and how the stage fused it.
struct SurfelReport {
  long count = 0;  // stable surfels: what map.ply holds
  // By where their depth came from (DepthSource names): stable count, their area (m^2), and the
  // unstable surfels not written.
  std::vector<std::pair<std::string, long>> by_source;
  std::vector<std::pair<std::string, double>> area_m2;
  std::vector<std::pair<std::string, long>> unstable;
  size_t bytes_per_surfel = 0;
  size_t memory_bytes = 0;
  std::vector<SurfelCountAt> count_over_time;
  std::string variant;  // the variant's name ("with_fill", "without_fill")
  size_t fills_fused = 0;
  StepTimes frame_ms, fill_ms;  // fusing a frame, fusing a keyframe's fill
  long merged_as_copies = 0;    // surfels merged into a copy of themselves
  long budget = 0;              // FusionOptions::max_surfels
  long removed_over_budget = 0;
  int failed_frames = 0, failed_fills = 0;
  std::optional<std::string> first_failure;          // what the first failed item threw
  int dropped_items = 0;                             // live input: found the queue full
  int corrections_applied = 0;                       // loop corrections the map followed
  // Clear objects at the end of the run (glass.revolution): groups of transparent surfels big
  // enough for a shape, those completed as surfaces of revolution, the surfels laid on them.
  int glass_objects = 0, glass_shapes = 0;
  int glass_shapes_from_outlines = 0;  // of them, those whose radius their outline gave
  long glass_shape_surfels = 0;
  long StableFrom(const std::string& source) const;  // by_source's count (0 when not there)
};

// A loop the pose graph accepted: the keyframe, the one it closed with, and whether the edges
// accepted moved the graph.
struct AcceptedLoop {
  std::string keyframe, with;
  bool correction = false;
};

// report.json's "loops": what the loop-closure stage searched, found and accepted.
struct LoopReport {
  bool enabled = false;  // false: the run had no loop closure (nothing else is written)
  int keyframes = 0, keyframes_dropped = 0, keyframes_stored = 0, keyframes_same_place = 0,
      keyframes_held = 0, keyframes_failed = 0;
  int candidates = 0, verified = 0, accepted = 0, rejected_by_graph = 0, pending_when_seen = 0;
  std::map<std::string, int> refused;  // reasons candidates were refused, without their figures
  int optimisations = 0;
  StepTimes optimisation_ms, keyframe_ms;
  int relocalisation_attempts = 0, relocalised = 0;
  size_t database_bytes = 0;
  std::vector<AcceptedLoop> loops;  // the first ones accepted
};

void to_json(nlohmann::ordered_json& j, const StepTimes& t);
void to_json(nlohmann::ordered_json& j, const FailedKeyframe& f);
void to_json(nlohmann::ordered_json& j, const ModelCompletionReport& m);
void to_json(nlohmann::ordered_json& j, const KeyframeFill& k);
void to_json(nlohmann::ordered_json& j, const FillReport& f);
void to_json(nlohmann::ordered_json& j, const SurfelCountAt& c);
void to_json(nlohmann::ordered_json& j, const SurfelReport& s);
void to_json(nlohmann::ordered_json& j, const AcceptedLoop& l);
void to_json(nlohmann::ordered_json& j, const LoopReport& l);

void from_json(const nlohmann::ordered_json& j, StepTimes& t);
void from_json(const nlohmann::ordered_json& j, FailedKeyframe& f);
void from_json(const nlohmann::ordered_json& j, ModelCompletionReport& m);
void from_json(const nlohmann::ordered_json& j, KeyframeFill& k);
void from_json(const nlohmann::ordered_json& j, FillReport& f);
void from_json(const nlohmann::ordered_json& j, SurfelCountAt& c);
void from_json(const nlohmann::ordered_json& j, SurfelReport& s);
void from_json(const nlohmann::ordered_json& j, AcceptedLoop& l);
void from_json(const nlohmann::ordered_json& j, LoopReport& l);

}  // namespace gf
