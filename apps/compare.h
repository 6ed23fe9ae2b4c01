// `glassfusion compare INPUT --out DIR`: track once, fuse twice (sensor plus fill; sensor only),
// and show what the fill adds to the model.
//
// Writes DIR/with_fill/ and DIR/without_fill/ (each a complete run folder: trajectory.txt,
// map.ply, report.json; keyframes/ in with_fill), DIR/compare.json and DIR/report.html with the
// surfel count over time of both maps, renderings of both from the same viewpoints and, where the
// input has ground truth (a synthetic capture: scene.ply, gt/depth/, groundtruth.txt), their
// completeness and accuracy overall and per material (surfels/completeness.h; the maps are moved
// into the ground truth's frame by the rigid transform that best maps the run's camera poses onto
// the true ones, AlignPoses: positions alone leave it undetermined when the camera moves along a
// line, as in a 40-frame orbit).
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
#include "apps/map_view.h"
#include "apps/reconstruct.h"
#include "apps/report_html.h"

namespace gf {

struct CompareSummary {
  ReconstructionSummary run;
  nlohmann::ordered_json compare;  // compare.json
  std::string BriefReport() const;
};

// options.out_dir is DIR; options.pipeline.fill and fusion are forced on.
CompareSummary RunCompare(const ReconstructOptions& options);

// The comparison in DIR = out_dir (as RunCompare wrote it) as report sections: both maps rendered
// from the same viewpoints, completeness and accuracy against ground truth, both maps' size over
// time, the trajectory, fill overlays, timings, settings and links. `prefix` is DIR seen from the
// report's folder ("" for DIR/report.html); `file` gives the paths of files written beside the
// report (the 3D view of both maps).
void AddComparisonSections(HtmlReport* r, const std::string& out_dir, const std::string& prefix,
                           const ReportFile& file);

// The ground-truth part of compare.json for one map (in the run's frame), or null when `input`
// has no ground truth.
nlohmann::ordered_json EvaluateMapAgainstTruth(const std::string& input,
                                               const std::string& run_dir);

// `glassfusion eval --map M --gt-mesh MESH`: the same for a map file, with the ground truth's and
// the run's trajectories (for the alignment). When MESH is a synthetic capture's scene.ply, its
// folder's true depth decides which surfaces were observed; otherwise every surface counts.
nlohmann::ordered_json EvaluateMapFiles(const std::string& map_path, const std::string& mesh_path,
                                        const Trajectory& gt, const Trajectory& est);

}  // namespace gf
