// `glassfusion reconstruct INPUT --out DIR`: the pipeline controller.
//
// Stages run in threads joined by bounded queues (DESIGN.md): a reader decodes frames while the
// tracker aligns the previous ones. Today the pipeline tracks the camera (frame-to-keyframe ICP);
// every new keyframe goes to the asynchronous stereo-fill stage (apps/fill_stage.h), which fills
// its depth holes from a partner keyframe; loop closure and surfel fusion join as they land.
//
// Outputs in DIR: trajectory.txt (TUM format, the input's depth timestamps), keyframes/ (hole
// mask, filled depth and overlay per keyframe, see fill_stage.h), camera.json (the intrinsics
// used) and report.json (complete, input, config, frames, fps, per-stage median/max
// milliseconds, keyframes, tracking losses, fill, warnings; loops/surfels are null until those
// stages exist). Each file is written atomically.
//
// No run is lost: when a run must stop (bad input in the middle of a capture, an output that
// cannot be written, SIGINT/SIGTERM through options.interrupt) it still writes trajectory.txt of
// the frames processed, camera.json and report.json with "complete": false and
// "stopped_because", then throws (InputError, or Interrupted for a signal). A keyframe whose fill
// fails is skipped and counted (fill_stage.h); the run goes on. DIR must be new or empty, or hold
// an earlier run and options.force be set (its contents are then removed first), so that old and
// new files never mix. The first frames' depth must be plausible (a median between 0.3 and 10 m,
// else the depth scale is wrong), and a run that loses tracking on most frames is refused unless
// options.allow_lost.
#pragma once

#include <atomic>
#include <string>
#include <vector>

#include "acquisition/frame_source.h"
#include "apps/fill_stage.h"
#include "registration/tracker.h"

namespace gf {

struct ReconstructOptions {
  std::string input;
  std::string out_dir;
  std::string config_file;  // --config FILE, applied (apps/config.h); listed in report.json
  int first_frame = 0;      // --frames A:B: skip frames before A
  int end_frame = -1;       // ... and stop before B (-1 = to the end)
  FrameSourceOptions source;
  TrackerOptions tracker;
  int queue_capacity = 8;  // frames buffered between reader and tracker
  bool fill = true;        // stereo hole filling of keyframes (--no-fill turns it off)
  FillStageOptions fill_options;
  bool force = false;       // --force: replace an earlier run in out_dir
  bool allow_lost = false;  // --allow-lost: accept a run that loses tracking on most frames
  // Set (to the signal's number) by a signal handler to stop the run early; may be null.
  const std::atomic<int>* interrupt = nullptr;
  bool Check(std::string* message = nullptr) const;
};

struct ReconstructSummary {
  int frames = 0;
  int lost = 0;
  int keyframes = 0;
  long hole_pixels = 0;  // in keyframes handed to the fill
  long filled_pixels = 0;
  double seconds = 0;
  double fps = 0;
  std::vector<std::string> warnings;  // also in report.json
  std::string BriefReport() const;
};

// Parses "A:B", "A:" or ":B" (whole non-negative frame numbers) into first/end frame. Throws
// InputError on anything else ("1e3:2000", "5:3", "a:b").
void ParseFrameRange(const std::string& range, int* first, int* end);

ReconstructSummary RunReconstruct(const ReconstructOptions& options);

}  // namespace gf
