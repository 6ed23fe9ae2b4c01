// `glassfusion demo`: the built-in demonstration behind `make demo`.
//
// Generates the built-in glass scene (synthetic Kinect v1, `glass-table`, with ground truth) into
// OUT/glass-table, reads it back through the same frame source a user's capture goes through and
// measures the sensor's holes per material (what the stereo fill exists for); then runs `compare`
// on it into OUT/compare (tracked once, fused with and without the fill, both maps scored against
// the ground truth) and scores the keyframes' fill per material against the true depth of what
// the colour camera sees. Writes OUT/report.json and OUT/report.html: the scene, holes and fill
// per material with a histogram of the fill's errors, then the comparison's sections (both maps
// rendered, completeness per material with and without the fill, the surfel count over time, the
// trajectory against ground truth, fill overlays, timings, settings, links), and the holes of every
// dataset folder found under --data. With a config file, the runs use its settings (and the report
// lists them), so that a setting's effect on each material can be measured on the demo scene.
//
// OUT is a RunFolder (acquisition/run_folder.h) and OUT/compare a run folder of its own: a demo
// run replaces the files an earlier demo listed in OUT's marker (and compare's in its own), never
// anything else; a non-empty OUT without a marker is refused, and so is a second demo into the
// same OUT while the first runs.
#pragma once

#include <string>

namespace gf {

struct DemoOptions {
  std::string out_dir = "demo-out";
  std::string data_dir;     // "" = ../shared/datasets when present
  int frames = 30;          // frames of the glass scene
  std::string config_file;  // --config FILE: tracker and fill settings for the reconstruction
                            // (pipeline/settings.h), as `reconstruct --config` takes them
  bool glass = true;        // false (--no-glass): no transparent surfels (FusionOptions::glass)
  bool Check(std::string* message = nullptr) const;
};

// Returns one line for the terminal: the scene, the comparison, where the report is.
std::string RunDemo(const DemoOptions& options);

}  // namespace gf
