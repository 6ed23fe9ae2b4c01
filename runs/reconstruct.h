// `glassfusion reconstruct INPUT --out DIR`: the pipeline (pipeline/reconstruction.h) over an
// input path, into a run folder, with terminal progress and Ctrl-C.
//
// Outputs in DIR (pipeline/run_sink.h): trajectory.txt, camera.json, report.json, keyframes/.
// DIR is a RunFolder (acquisition/run_folder.h): it must be new or empty, or hold an earlier run
// and `force` be set, which removes only the files that run's marker lists; it must not be, hold
// or lie inside the input, and no other run may be writing it. A run that must stop still
// writes what it processed with "complete": false (see reconstruction.h) and then throws:
// InputError for bad input or an output that cannot be written, Interrupted for Ctrl-C/SIGTERM
// (through `interrupt`). A run refused as not usable (tracking lost on most frames unless
// allow_lost, an empty map, a stage that failed on everything: ReconstructionSummary::refused)
// throws InputError after writing its outputs. mesh.ply and report.html are written before the
// final report.json.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "acquisition/frame_source.h"
#include "acquisition/run_folder.h"
#include "pipeline/reconstruction.h"
#include "pipeline/run_sink.h"

namespace gf {

struct ReconstructOptions {
  std::string input;
  std::string out_dir;
  std::string config_file;  // --config FILE, applied (pipeline/settings.h); listed in report.json
  FrameSourceOptions source;
  ReconstructionOptions pipeline;  // frames, tracker, fill
  bool force = false;              // --force: replace (only) the earlier run's files in out_dir
  bool allow_lost = false;         // --allow-lost: accept a run that loses tracking on most frames
  bool mesh = false;  // --mesh: also mesh.ply, a triangle mesh of the map (surfels/mesh.h)
  // Set (to the signal's number) by a signal handler to stop the run early; may be null.
  const std::atomic<int>* interrupt = nullptr;
  bool Check(std::string* message = nullptr) const;
};

ReconstructionSummary RunReconstruct(const ReconstructOptions& options);

// Checks `options` and opens the input, before any run folder (a bad input leaves none behind);
// *folder gets the run folder's options (--force, the input it must not hold). Throws InputError.
std::unique_ptr<FrameSource> OpenRunInput(const ReconstructOptions& options,
                                          RunFolder::Options* folder);

// The pipeline over `source` (opened from options.input) into `sink` (and `without_fill`, may be
// null: see Reconstruction::Run), with terminal progress labelled `label` and Ctrl-C; `finish`
// (may be empty) as ReconstructionCallbacks::finish. Throws as RunReconstruct does.
ReconstructionSummary RunPipeline(
    const ReconstructOptions& options, FrameSource* source, RunSink* sink, RunSink* without_fill,
    const std::string& label,
    const std::function<void(const RunReport& report)>& finish = {});

}  // namespace gf
