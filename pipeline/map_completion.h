// The map's completion of the keyframes, the last step of a run with fill and fusion (called by
// Reconstruction::Run after the stages have finished).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "acquisition/trajectory.h"
#include "pipeline/fill_stage.h"
#include "pipeline/fusion_stage.h"
#include "pipeline/run_sink.h"
#include "pipeline/stage_reports.h"

namespace gf {

// Each filled keyframe's holes that its own fill left empty, completed from the final model's
// fills at the keyframe's final pose, on every core (the keyframes are independent, so the
// outputs do not depend on which thread did which). A keyframe that cannot be completed stays as
// its fill left it (a warning); the others go on. `stop` is asked on this thread between its
// keyframes (true: the keyframes not started stay as they are). Returns report.json's
// fill.model_completion.
// `names[i]` is the frame name of trajectory entry i; warnings are appended to *warnings.
ModelCompletionReport CompleteFromMap(const FillStage& fill, FusionStage* fusion,
                                      const Trajectory& trajectory,
                                      const std::vector<std::string>& names, RunSink* sink,
                                      const std::function<bool()>& stop,
                                      std::vector<std::string>* warnings);

// The colour images of up to `count` of the filled keyframes, evenly spaced over the run, at
// their poses in `trajectory` (names as above), read from `sink` one at a time when asked for
// (FusionStage::Finish's views for the clear objects' outlines). `sink` must outlive the views.
OutlineViews KeyframeViews(const FillStage& fill, const Trajectory& trajectory,
                           const std::vector<std::string>& names, const RunSink& sink, int count);

}  // namespace gf
