// Scoring a surfel map against a synthetic capture's ground truth (glassfusion synth): its mesh,
// materials, true poses and true depth. The map is moved into the ground truth's frame by the
// rigid transform that best maps the run's camera poses onto the true ones (AlignPoses: positions
// alone leave it undetermined when the camera moves along a line, as in a 40-frame orbit), then
// scored by surfels/completeness.h: completeness overall and per material ({"within_1cm",
// "within_2cm"} as shares 0-1, "observed_samples") and accuracy ({"median_m", "p90_m",
// "fill_median_m", "fill_p90_m" over the stereo fill's surfels, "transparent_median_m",
// "transparent_p90_m" over the transparent ones}), and "ate_m".
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "acquisition/trajectory.h"

namespace gf {

// The ground-truth part of compare.json for one run's map (in the run's frame), or null when
// `input` has no ground truth (scene.ply, groundtruth.txt, depth.txt, camera.json, gt/depth/).
nlohmann::ordered_json EvaluateMapAgainstTruth(const std::string& input,
                                               const std::string& run_dir);

// `glassfusion eval --map M --gt-mesh MESH`: the same for a map file, with the ground truth's and
// the run's trajectories (for the alignment). When MESH is a synthetic capture's scene.ply, its
// folder's true depth decides which surfaces were observed; otherwise every surface counts.
nlohmann::ordered_json EvaluateMapFiles(const std::string& map_path, const std::string& mesh_path,
                                        const Trajectory& gt, const Trajectory& est);

}  // namespace gf
