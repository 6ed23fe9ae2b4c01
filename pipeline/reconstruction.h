// The reconstruction as a library: read, track, fill and fusion stages, each in its own thread,
// joined by bounded queues (stages.h, fill_stage.h, fusion_stage.h), over any FrameSource,
// writing through a RunSink (run_sink.h), reporting progress through callbacks. Loop closure
// joins as a stage of its own.
//
// No run is lost. A keyframe whose fill fails is skipped and counted; the run goes on. When the
// run must stop (a frame that cannot be read, an implausible depth scale, a keyframe that cannot
// be written, or callbacks.stop returning a reason such as "interrupted by SIGINT"), it still
// writes the trajectory of the frames processed, the camera and the report with "complete":
// false, "stopped_because" and "stopped_during" (the phase: tracking, fill, loop closure, fusion,
// map completion); then Run() rethrows what stopped it (or, for a stop request, returns with
// summary.complete false).
//
// "complete" tells the truth: true only when every step the run promises has finished, the
// keyframes' completion from the map included. A run whose result is not usable is not complete
// either (summary.refused, with the reason): tracking lost on most frames (unless allow_lost),
// a stage that failed on every frame or keyframe it was given (fusion, fill), an empty map.
// report.json is the last file written: until the run has finished, the report on disk says
// "complete": false, so a run killed at any moment never leaves one that says complete.
//
// Reproducible: for recorded input (a source that knows its frame count) every output but the
// report's timings is the same on every run and every machine: the stages overlap in threads, but
// what joins the map, and when, is fixed by the frame sequence (fusion_stage.h); a relocalisation
// searches every keyframe before it. Live input may drop work to keep up.
//
// Usage (as BAD SLAM's and COLMAP's controllers):
//   gf::Reconstruction reconstruction(options);
//   gf::FolderRunSink sink("run", /*replace=*/false);
//   gf::ReconstructionSummary s = reconstruction.Run(*source, &sink, callbacks);
//
// With loop closure (the default), trajectory.txt and the maps hold the poses corrected by the
// pose graph at the end of the run; frames whose tracking was lost have no line in trajectory.txt
// (report.json lists them).
//
// Thread-safety: Run() blocks the calling thread, from which every callback is called.
#pragma once

#include <exception>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/frame_source.h"
#include "pipeline/fill_stage.h"
#include "pipeline/fusion_stage.h"
#include "pipeline/loop_stage.h"
#include "pipeline/run_report.h"
#include "pipeline/run_sink.h"
#include "registration/tracker.h"

namespace gf {

struct ReconstructionOptions {
  int first_frame = 0;     // frames before this are read but not processed
  int end_frame = -1;      // ... and reading stops here (-1 = to the end)
  int queue_capacity = 8;  // frames buffered between reader and tracker
  TrackerOptions tracker;
  bool fill = true;  // stereo hole filling of keyframes
  FillStageOptions fill_options;
  bool fusion = true;  // the surfel map (map.ply)
  // Track against the model (the surfel map rendered at the last pose) after the keyframe; needs
  // fusion. Tracking then waits for each frame to be fused before the next.
  bool frame_to_model = false;
  FusionStageOptions fusion_options;
  bool loop_closure = true;  // loop closure, pose graph and relocalisation
  LoopStageOptions loop_options;
  // Accept a run that loses tracking on more than kMostFramesLost of its frames (a warning);
  // without it such a run is refused (its trajectory is not usable).
  bool allow_lost = false;
  // The file an implausible depth scale is blamed on (the camera.json in use); "" = the input.
  std::string camera_file;
  // Written into the report (config.file, input.path), not read.
  std::string config_file, input_path;
  bool Check(std::string* message = nullptr) const;
};

struct ReconstructionProgress {
  int frames = 0;              // tracked so far
  std::optional<int> total;    // frames expected, when the source knows
  int keyframes_offered = 0;   // handed to the fill
  int keyframes_filled = 0;    // filled and written
  int keyframes_searched = 0;  // searched for loops
  int frames_fused = 0;        // fused into the surfel map
  bool tracking_done = false;  // the fill and fusion are finishing the last keyframes
};

struct ReconstructionCallbacks {
  // About every 50 ms while the run goes on, and once at the end.
  std::function<void(const ReconstructionProgress&)> progress;
  // Asked as often: a non-empty reason stops the run (e.g. "interrupted by SIGINT").
  std::function<std::string()> stop;
  // Once a complete run's other outputs are written, before its report.json (the last file):
  // outputs made from the finished run (a mesh, report.html), given the report about to be
  // written. What it throws becomes a warning in that report.
  std::function<void(const RunReport& report)> finish;
};

// A run that loses tracking on more than this share of its frames has no usable trajectory.
constexpr double kMostFramesLost = 0.5;

struct ReconstructionSummary {
  bool complete = false;
  std::string stopped_because;  // when not complete
  std::string stopped_during;   // ... the phase: tracking, fill, loop closure, fusion, ...
  // Not complete because the result is not usable (stopped_because says why), rather than stopped.
  bool refused = false;
  int frames = 0;
  int lost = 0;
  int keyframes = 0;
  long hole_pixels = 0;  // in keyframes handed to the fill
  long filled_pixels = 0;
  long surfels = 0;        // in map.ply
  double seconds = 0;      // the whole run: the fill's tail after tracking and the map's
                           // completion of the keyframes included
  double fps = 0;          // frames / seconds
  bool most_lost = false;  // tracking was lost on more than kMostFramesLost of the frames
  std::vector<std::string> warnings;           // also in the report
  RunReport report;               // report.json as written
  RunReport report_without_fill;  // ... in the without_fill folder, when there is one
  long surfels_without_fill = 0;
  int loops = 0;  // loop edges in the optimised pose graph
  std::string BriefReport() const;
};

class Reconstruction {
 public:
  // Throws InputError when options.Check() fails.
  explicit Reconstruction(ReconstructionOptions options);
  // Runs over `source`, writing to `sink`. See the file comment for how a run ends.
  // `without_fill` (may be null): a second run folder for the same frames fused without the fill
  // (compare); it gets the same trajectory and camera, its own map.ply and report.json (whose
  // fill is null). It needs fill and fusion on.
  ReconstructionSummary Run(FrameSource& source, RunSink* sink,
                            const ReconstructionCallbacks& callbacks = {},
                            RunSink* without_fill = nullptr);

 private:
  struct Stages;
  std::unique_ptr<Stages> MakeStages(FrameSource& source, RunSink* sink, RunSink* without_fill,
                                     bool live) const;
  // report.json's stages.cpu_seconds: each stage's threads, the process's, the cores used.
  static CpuSecondsReport CpuReportOf(const Stages& s, double process_cpu_s, double seconds);
  ReconstructionSummary Summarise(const FrameSource& source, const Stages& s,
                                  const std::exception_ptr& error, const std::string& stop_reason,
                                  double seconds) const;
  // A run that finished but whose result is not usable: refused, with the reason.
  void RefuseIfUnusable(const Stages& s, ReconstructionSummary* summary) const;
  // The trajectory and, until the run has finished, a report that says it has not.
  void WriteOutputs(const Stages& s, RunSink* sink, RunSink* without_fill,
                    const ReconstructionSummary& summary) const;
  // After a complete run's outputs are written: each keyframe completed from the final map
  // (FusionStageOptions::complete_keyframes), recorded in the report's fill.model_completion.
  // `stop` (true) leaves the keyframes not yet completed as they are: the run is then not
  // complete.
  void CompleteKeyframes(const Stages& s, RunSink* sink, const std::function<bool()>& stop,
                         const std::string& stop_reason, ReconstructionSummary* summary) const;
  // The finish callback (complete runs), then report.json: the without-fill folder's, and the
  // run's last of all.
  void WriteFinalReports(const ReconstructionCallbacks& callbacks, RunSink* sink,
                         RunSink* without_fill, ReconstructionSummary* summary) const;
  ReconstructionOptions options_;
};

}  // namespace gf
