// `glassfusion reconstruct INPUT --out DIR`: the pipeline controller.
//
// Stages run in threads joined by bounded queues (DESIGN.md): a reader decodes frames while the
// tracker aligns the previous ones. Today the pipeline tracks the camera (frame-to-keyframe ICP);
// every new keyframe goes to the asynchronous stereo-fill stage (apps/fill_stage.h), which fills
// its depth holes from a partner keyframe; loop closure and surfel fusion join as they land.
//
// Outputs in DIR: trajectory.txt (TUM format, the input's depth timestamps), keyframes/ (hole
// mask, filled depth and overlay per keyframe, see fill_stage.h), camera.json (the intrinsics
// used) and report.json (input, config, frames, fps, per-stage median/max milliseconds,
// keyframes, tracking losses, fill; loops/surfels are null until those stages exist). Each file is
// written atomically.
#pragma once

#include <string>

#include "acquisition/frame_source.h"
#include "apps/fill_stage.h"
#include "registration/tracker.h"

namespace gf {

struct ReconstructOptions {
  std::string input;
  std::string out_dir;
  std::string config_file;  // --config FILE, applied (apps/config.h); listed in report.json
  int first_frame = 0;  // --frames A:B: skip frames before A
  int end_frame = -1;   // ... and stop before B (-1 = to the end)
  FrameSourceOptions source;
  TrackerOptions tracker;
  int queue_capacity = 8;  // frames buffered between reader and tracker
  bool fill = true;        // stereo hole filling of keyframes (--no-fill turns it off)
  FillStageOptions fill_options;
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
  std::string BriefReport() const;
};

// Parses "A:B", "A:" or ":B" into first/end frame. Throws InputError on anything else.
void ParseFrameRange(const std::string& range, int* first, int* end);

ReconstructSummary RunReconstruct(const ReconstructOptions& options);

}  // namespace gf
