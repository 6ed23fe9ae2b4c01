// `glassfusion demo`: the built-in demonstration behind `make demo`.
//
// Generates the built-in glass scene (synthetic Kinect v1, `glass-table`, with ground truth) into
// OUT/glass-table, reads it back through the same frame source a user's capture goes through, and
// writes OUT/report.json and OUT/report.html: the sensor's holes per material (what the stereo
// fill exists for), an overview image of the first frame, and the holes of every dataset folder
// found under --data; then reconstructs the scene into OUT/run (tracking + stereo fill) and
// reports the trajectory error and, per material, how many keyframe holes were filled and how
// well (against the ground-truth depth of what the colour camera sees), with a fill overlay.
// With a config file, the reconstruction uses its settings (and report.json lists them), so that
// a setting's effect on each material can be measured on the demo scene.
#pragma once

#include <string>

namespace gf {

struct DemoOptions {
  std::string out_dir = "demo-out";
  std::string data_dir;     // "" = ../shared/datasets when present
  int frames = 30;          // frames of the glass scene
  std::string config_file;  // --config FILE: tracker and fill settings for the reconstruction
                            // (pipeline/settings.h), as `reconstruct --config` takes them
  bool Check(std::string* message = nullptr) const;
};

void RunDemo(const DemoOptions& options);

}  // namespace gf
