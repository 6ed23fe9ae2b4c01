// `glassfusion compare INPUT --out DIR`: track once, fuse twice (sensor plus fill; sensor only),
// and show what the fill adds to the model.
//
// Writes DIR/with_fill/ and DIR/without_fill/ (each a complete run folder: trajectory.txt,
// map.ply, report.json; keyframes/ in with_fill), renderings of both maps from the same
// viewpoints, DIR/compare.json and DIR/report.html (report/compare_report.h); where the input has
// ground truth (a synthetic capture: scene.ply, gt/depth/, groundtruth.txt), both maps'
// completeness and accuracy overall and per material (eval/map_truth.h).
//
// DIR is one RunFolder (acquisition/run_folder.h) for all of it: one marker lists the files of
// both runs and the comparison's own, one lock keeps other runs out; --force removes only those.
//
// compare.json: {"with_fill": {...}, "without_fill": {...}}, each with "surfels" (report.json's)
// and, with ground truth, "completeness" ({"overall", "per_material": {name: ...}}, each
// {"within_1cm", "within_2cm"} as shares 0-1) and "accuracy" ({"median_m", "p90_m",
// "fill_median_m", "fill_p90_m" over the fill's surfels, "transparent_median_m",
// "transparent_p90_m" over the transparent ones: clear glass, FusionOptions::glass}); "ate_m".
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "acquisition/trajectory.h"
#include "runs/reconstruct.h"

namespace gf {

struct CompareSummary {
  ReconstructionSummary run;
  nlohmann::ordered_json compare;  // compare.json
  std::string BriefReport() const;
};

// options.out_dir is DIR; options.pipeline.fill and fusion are forced on.
CompareSummary RunCompare(const ReconstructOptions& options);

}  // namespace gf
