// report.json as a type: what a run says of itself (DESIGN.md names its keys; they are the
// fields' names here). Reconstruction::Run builds it from the stages' reports
// (pipeline/stage_reports.h); the sinks write it, RunReader reads it back, and the pages, compare
// and batch read its fields. to_json and from_json (run_report.cc) are the only code that knows
// its JSON; a key absent from an older report leaves its field's default.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "pipeline/stage_reports.h"

namespace gf {

// What the run read.
struct RunInputReport {
  std::string path;  // as given
  std::string kind;  // FrameSource::Kind(): "tum", "icl", "oni", ...
  int first_frame = 0;
  int end_frame = -1;  // negative: to the end
};

// How the run was configured.
struct RunConfigReport {
  std::string tracker;  // "frame_to_keyframe_icp" or "frame_to_keyframe_then_model_icp"
  bool stereo_fill = false, surfel_fusion = false, loop_closure = false;
  std::string threads;  // the stage threads, in words
  unsigned hardware_concurrency = 0;
  std::optional<std::string> file;  // the --config file read, if any
  nlohmann::ordered_json settings;  // every setting (pipeline/settings.h writes and reads it)
};

// CPU seconds each stage's own threads used; `other` the rest of the process (OpenCV's worker
// pool, which runs the stages' parallel loops, and the calling thread), `process` all of it,
// cores_used = process / wall seconds, beside the machine's cores.
struct CpuSecondsReport {
  std::vector<std::pair<std::string, double>> stages;  // read, track, fill, fusion, loop_closure
  double other = 0, process = 0, cores_used = 0;
  unsigned cores = 0;
};

// How long each stage's steps took (read, track, stereo, fusion, fusion_fill, loop_closure: the
// stages the run had), the CPU time and the peak resident memory (MiB).
struct StagesReport {
  std::vector<std::pair<std::string, StepTimes>> steps;
  std::optional<CpuSecondsReport> cpu_seconds;
  std::optional<double> peak_resident_mib;
  const StepTimes* Find(const std::string& stage) const;
};

struct TrackingReport {
  int lost_frames = 0, relocalised = 0, restarted = 0;
  std::vector<std::string> lost;  // the first lost frames' names
};

struct RunReport {
  bool complete = false;
  std::string stopped_because, stopped_during;  // when not complete
  RunInputReport input;
  RunConfigReport config;
  int frames = 0;
  double fps = 0, seconds = 0;  // the whole run, the map's completion included
  StagesReport stages;
  int keyframes = 0;
  TrackingReport tracking;
  LoopReport loops;
  std::optional<FillReport> fill;       // runs with the fill
  std::optional<SurfelReport> surfels;  // runs with the fusion
  std::vector<std::string> warnings;
};

void to_json(nlohmann::ordered_json& j, const RunConfigReport& c);
void to_json(nlohmann::ordered_json& j, const CpuSecondsReport& c);
void to_json(nlohmann::ordered_json& j, const RunReport& r);
void from_json(const nlohmann::ordered_json& j, RunConfigReport& c);
void from_json(const nlohmann::ordered_json& j, CpuSecondsReport& c);
void from_json(const nlohmann::ordered_json& j, RunReport& r);

}  // namespace gf
