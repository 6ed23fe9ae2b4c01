#include "pipeline/stage_reports.h"

#include <algorithm>

#include "acquisition/stats.h"
#include "pipeline/json_fields.h"

namespace gf {
namespace {

using json = nlohmann::ordered_json;
using json_fields::Object;
using json_fields::OrNull;
using json_fields::Read;

// One more of `name` in `counts` (added at the end when new).
void Count(const std::string& name, std::vector<std::pair<std::string, int>>* counts) {
  for (auto& [n, count] : *counts)
    if (n == name) {
      ++count;
      return;
    }
  counts->push_back({name, 1});
}

}  // namespace

StepTimes StepTimes::Of(std::vector<double> ms) {
  StepTimes t;
  t.count = ms.size();
  if (ms.empty()) return t;
  std::sort(ms.begin(), ms.end());
  t.median_ms = ms[ms.size() / 2];
  t.max_ms = ms.back();
  return t;
}

long SurfelReport::StableFrom(const std::string& source) const {
  for (const auto& [name, count] : by_source)
    if (name == source) return count;
  return 0;
}

FillReport FillReport::Of(const std::vector<KeyframeFill>& keyframes, int dropped, int not_filled) {
  FillReport r;
  r.pair_paths = {{"rectified_sgbm", 0},
                  {"plane_sweep_forward", 0},
                  {"plane_sweep_degenerate_rectification", 0},
                  {"plane_sweep_requested", 0},
                  {"none", 0}};
  r.sgbm_refused = {{"valid_region", 0}, {"disparity_range", 0}};
  std::vector<double> errors, ms;
  for (const KeyframeFill& k : keyframes) {
    if (!k.failure.empty()) r.failed_keyframes.push_back({k.timestamp, k.failure});
    if (!k.path.empty()) Count(k.path, &r.pair_paths);
    if (!k.sgbm_refused.empty()) Count(k.sgbm_refused, &r.sgbm_refused);
    r.sgbm_rescaled += k.sgbm_rescaled;
    r.sgbm_vertical += k.sgbm_vertical;
    r.hole_pixels += k.hole_pixels;
    r.filled_pixels += k.filled_pixels;
    r.carried_pixels += k.carried_pixels;
    r.corrected_pixels += k.corrected_pixels;
    r.corroborated_pixels += k.corroborated_pixels;
    r.seen_through_pixels += k.seen_through_pixels;
    if (!k.partner.empty()) {
      ++r.keyframes_paired;
      ms.push_back(k.ms);
      if (k.filled_pixels > 0) errors.push_back(k.stereo_error_median_m);
    }
  }
  if (!errors.empty()) r.stereo_error_median_m = Median(errors);
  const StepTimes pair_times = StepTimes::Of(ms);
  r.pair_median_ms = pair_times.median_ms;
  r.pair_max_ms = pair_times.max_ms;
  r.keyframes_filled = static_cast<int>(keyframes.size());
  r.keyframes_dropped = dropped;
  r.keyframes_not_filled = not_filled;
  r.per_keyframe = keyframes;
  return r;
}

void to_json(json& j, const StepTimes& t) {
  j = {{"median_ms", OrNull(t.median_ms)}, {"max_ms", OrNull(t.max_ms)}, {"count", t.count}};
}

void to_json(json& j, const FailedKeyframe& f) {
  j = {{"timestamp", f.timestamp}, {"reason", f.reason}};
}

void to_json(json& j, const ModelCompletionReport& m) {
  j = {{"keyframes", m.keyframes},
       {"pixels", m.pixels},
       {"seconds", m.seconds},
       {"stopped", m.stopped},
       {"keyframes_done", m.keyframes_done},
       {"keyframes_to_do", m.keyframes_to_do},
       {"glass_keyframes", m.glass_keyframes},
       {"glass_pixels", m.glass_pixels}};
}

void to_json(json& j, const KeyframeFill& k) {
  j = {{"timestamp", k.timestamp},
       {"partner", OrNull(k.partner)},
       {"baseline_m", k.baseline_m},
       {"matches", k.matches},
       {"third", OrNull(k.third)},
       {"third_view", k.third_view},
       {"method", k.method},
       {"path", OrNull(k.path)},
       {"sgbm_vertical", k.sgbm_vertical},
       {"hole_pixels", k.hole_pixels},
       {"filled_pixels", k.filled_pixels},
       {"carried_pixels", k.carried_pixels},
       {"corrected_pixels", k.corrected_pixels},
       {"witnesses", k.witnesses},
       {"corroborated_pixels", k.corroborated_pixels},
       {"seen_through_pixels", k.seen_through_pixels},
       {"fill_rate", k.hole_pixels ? double(k.filled_pixels) / k.hole_pixels : 0.0},
       {"stereo_error_median_m", k.stereo_error_median_m},
       {"ms", k.ms},
       {"termination", k.termination}};
}

void to_json(json& j, const FillReport& f) {
  j = {{"hole_pixels", f.hole_pixels},
       {"filled_pixels", f.filled_pixels},
       {"fill_rate", f.fill_rate()},
       {"carried_pixels", f.carried_pixels},
       {"corrected_pixels", f.corrected_pixels},
       {"corroborated_pixels", f.corroborated_pixels},
       {"seen_through_pixels", f.seen_through_pixels},
       {"stereo_error_median_m", OrNull(f.stereo_error_median_m)},
       {"keyframes_filled", f.keyframes_filled},
       {"keyframes_paired", f.keyframes_paired},
       {"keyframes_dropped", f.keyframes_dropped},
       {"keyframes_not_filled", f.keyframes_not_filled},
       {"failed_keyframes", f.failed_keyframes},
       {"pair_paths", Object(f.pair_paths)},
       {"sgbm_refused", Object(f.sgbm_refused)},
       {"sgbm_rescaled", f.sgbm_rescaled},
       {"sgbm_vertical", f.sgbm_vertical},
       {"pair_median_ms", OrNull(f.pair_median_ms)},
       {"pair_max_ms", OrNull(f.pair_max_ms)},
       {"per_keyframe", f.per_keyframe}};
  if (f.model_completion) j["model_completion"] = *f.model_completion;
}

void to_json(json& j, const SurfelCountAt& c) {
  j = {{"frame", c.frame},
       {"stable", c.stable},
       {"sensor", c.sensor},
       {"stereo_fill", c.stereo_fill},
       {"unstable", c.unstable}};
}

void to_json(json& j, const SurfelReport& s) {
  j = {{"count", s.count},
       {"by_source", Object(s.by_source)},
       {"area_m2", Object(s.area_m2)},
       {"unstable", Object(s.unstable)},
       {"bytes_per_surfel", s.bytes_per_surfel},
       {"memory_bytes", s.memory_bytes},
       {"count_over_time", s.count_over_time},
       {"variant", s.variant},
       {"fills_fused", s.fills_fused},
       {"frame_ms", s.frame_ms},
       {"fill_ms", s.fill_ms},
       {"merged_as_copies", s.merged_as_copies},
       {"budget", s.budget},
       {"removed_over_budget", s.removed_over_budget},
       {"failed_items", s.failed_frames + s.failed_fills},
       {"failed_frames", s.failed_frames},
       {"failed_fills", s.failed_fills},
       {"first_failure", OrNull(s.first_failure)},
       {"dropped_items", s.dropped_items},
       {"corrections_applied", s.corrections_applied},
       {"glass_objects", s.glass_objects},
       {"glass_shapes", s.glass_shapes},
       {"glass_shapes_from_outlines", s.glass_shapes_from_outlines},
       {"glass_shape_surfels", s.glass_shape_surfels}};
}

void to_json(json& j, const AcceptedLoop& l) {
  j = {{"keyframe", l.keyframe}, {"with", l.with}, {"correction", l.correction}};
}

void to_json(json& j, const LoopReport& l) {
  if (!l.enabled) {
    j = {{"enabled", false}};
    return;
  }
  j = {{"enabled", true},
       {"keyframes", l.keyframes},
       {"keyframes_dropped", l.keyframes_dropped},
       {"keyframes_stored", l.keyframes_stored},
       {"keyframes_same_place", l.keyframes_same_place},
       {"keyframes_held", l.keyframes_held},
       {"keyframes_failed", l.keyframes_failed},
       {"candidates", l.candidates},
       {"verified", l.verified},
       {"accepted", l.accepted},
       {"rejected_by_graph", l.rejected_by_graph},
       {"pending_when_seen", l.pending_when_seen},
       {"refused", l.refused},
       {"optimisations", l.optimisations},
       {"optimisation_ms", l.optimisation_ms},
       {"keyframe_ms", l.keyframe_ms},
       {"relocalisation", {{"attempts", l.relocalisation_attempts}, {"found", l.relocalised}}},
       {"database_bytes", l.database_bytes},
       {"loops", l.loops}};
}

void from_json(const json& j, StepTimes& t) {
  Read(j, "median_ms", &t.median_ms);
  Read(j, "max_ms", &t.max_ms);
  Read(j, "count", &t.count);
}

void from_json(const json& j, FailedKeyframe& f) {
  Read(j, "timestamp", &f.timestamp);
  Read(j, "reason", &f.reason);
}

void from_json(const json& j, ModelCompletionReport& m) {
  Read(j, "keyframes", &m.keyframes);
  Read(j, "pixels", &m.pixels);
  Read(j, "seconds", &m.seconds);
  Read(j, "stopped", &m.stopped);
  Read(j, "keyframes_done", &m.keyframes_done);
  Read(j, "keyframes_to_do", &m.keyframes_to_do);
  Read(j, "glass_keyframes", &m.glass_keyframes);
  Read(j, "glass_pixels", &m.glass_pixels);
}

void from_json(const json& j, KeyframeFill& k) {
  Read(j, "timestamp", &k.timestamp);
  Read(j, "partner", &k.partner);
  Read(j, "baseline_m", &k.baseline_m);
  Read(j, "matches", &k.matches);
  Read(j, "third", &k.third);
  Read(j, "third_view", &k.third_view);
  Read(j, "method", &k.method);
  Read(j, "path", &k.path);
  Read(j, "sgbm_vertical", &k.sgbm_vertical);
  Read(j, "hole_pixels", &k.hole_pixels);
  Read(j, "filled_pixels", &k.filled_pixels);
  Read(j, "carried_pixels", &k.carried_pixels);
  Read(j, "corrected_pixels", &k.corrected_pixels);
  Read(j, "witnesses", &k.witnesses);
  Read(j, "corroborated_pixels", &k.corroborated_pixels);
  Read(j, "seen_through_pixels", &k.seen_through_pixels);
  Read(j, "stereo_error_median_m", &k.stereo_error_median_m);
  Read(j, "ms", &k.ms);
  Read(j, "termination", &k.termination);
}

void from_json(const json& j, FillReport& f) {
  Read(j, "hole_pixels", &f.hole_pixels);
  Read(j, "filled_pixels", &f.filled_pixels);
  Read(j, "carried_pixels", &f.carried_pixels);
  Read(j, "corrected_pixels", &f.corrected_pixels);
  Read(j, "corroborated_pixels", &f.corroborated_pixels);
  Read(j, "seen_through_pixels", &f.seen_through_pixels);
  Read(j, "stereo_error_median_m", &f.stereo_error_median_m);
  Read(j, "keyframes_filled", &f.keyframes_filled);
  Read(j, "keyframes_paired", &f.keyframes_paired);
  Read(j, "keyframes_dropped", &f.keyframes_dropped);
  Read(j, "keyframes_not_filled", &f.keyframes_not_filled);
  Read(j, "failed_keyframes", &f.failed_keyframes);
  Read(j, "pair_paths", &f.pair_paths);
  Read(j, "sgbm_refused", &f.sgbm_refused);
  Read(j, "sgbm_rescaled", &f.sgbm_rescaled);
  Read(j, "sgbm_vertical", &f.sgbm_vertical);
  Read(j, "pair_median_ms", &f.pair_median_ms);
  Read(j, "pair_max_ms", &f.pair_max_ms);
  Read(j, "per_keyframe", &f.per_keyframe);
  Read(j, "model_completion", &f.model_completion);
}

void from_json(const json& j, SurfelCountAt& c) {
  Read(j, "frame", &c.frame);
  Read(j, "stable", &c.stable);
  Read(j, "sensor", &c.sensor);
  Read(j, "stereo_fill", &c.stereo_fill);
  Read(j, "unstable", &c.unstable);
}

void from_json(const json& j, SurfelReport& s) {
  Read(j, "count", &s.count);
  Read(j, "by_source", &s.by_source);
  Read(j, "area_m2", &s.area_m2);
  Read(j, "unstable", &s.unstable);
  Read(j, "bytes_per_surfel", &s.bytes_per_surfel);
  Read(j, "memory_bytes", &s.memory_bytes);
  Read(j, "count_over_time", &s.count_over_time);
  Read(j, "variant", &s.variant);
  Read(j, "fills_fused", &s.fills_fused);
  Read(j, "frame_ms", &s.frame_ms);
  Read(j, "fill_ms", &s.fill_ms);
  Read(j, "merged_as_copies", &s.merged_as_copies);
  Read(j, "budget", &s.budget);
  Read(j, "removed_over_budget", &s.removed_over_budget);
  Read(j, "failed_frames", &s.failed_frames);
  Read(j, "failed_fills", &s.failed_fills);
  Read(j, "first_failure", &s.first_failure);
  Read(j, "dropped_items", &s.dropped_items);
  Read(j, "corrections_applied", &s.corrections_applied);
  Read(j, "glass_objects", &s.glass_objects);
  Read(j, "glass_shapes", &s.glass_shapes);
  Read(j, "glass_shapes_from_outlines", &s.glass_shapes_from_outlines);
  Read(j, "glass_shape_surfels", &s.glass_shape_surfels);
}

void from_json(const json& j, AcceptedLoop& l) {
  Read(j, "keyframe", &l.keyframe);
  Read(j, "with", &l.with);
  Read(j, "correction", &l.correction);
}

void from_json(const json& j, LoopReport& l) {
  Read(j, "enabled", &l.enabled);
  Read(j, "keyframes", &l.keyframes);
  Read(j, "keyframes_dropped", &l.keyframes_dropped);
  Read(j, "keyframes_stored", &l.keyframes_stored);
  Read(j, "keyframes_same_place", &l.keyframes_same_place);
  Read(j, "keyframes_held", &l.keyframes_held);
  Read(j, "keyframes_failed", &l.keyframes_failed);
  Read(j, "candidates", &l.candidates);
  Read(j, "verified", &l.verified);
  Read(j, "accepted", &l.accepted);
  Read(j, "rejected_by_graph", &l.rejected_by_graph);
  Read(j, "pending_when_seen", &l.pending_when_seen);
  Read(j, "refused", &l.refused);
  Read(j, "optimisations", &l.optimisations);
  Read(j, "optimisation_ms", &l.optimisation_ms);
  Read(j, "keyframe_ms", &l.keyframe_ms);
  if (j.contains("relocalisation")) {
    Read(j["relocalisation"], "attempts", &l.relocalisation_attempts);
    Read(j["relocalisation"], "found", &l.relocalised);
  }
  Read(j, "database_bytes", &l.database_bytes);
  Read(j, "loops", &l.loops);
}

}  // namespace gf
