// The settings tree of a reconstruction: the tracker's and the fill's settings as JSON, for
// report.json's config.settings and for `glassfusion reconstruct|bench|demo --config FILE`.
//
// The file holds any part of the tree that SettingsToJson writes (report.json's config.settings
// holds the whole tree of a run, so a run's settings can be fed back):
//   {"tracker": {"pyramid_levels": 3, "icp": {...}, "surf": {...}, "match": {...},
//                "ransac": {...}, "keyframes": {...}, ...},
//    "fill": {"queue_capacity": 16, "geometry": {...}, "pairs": {...},
//             "stereo": {"sgbm": {...}, "plane_sweep": {...}, "depth_steps": {...},
//                        "see_through": {...}, "validation": {...}, "photometric": {...}, ...},
//             "carry": {...}},
//    "fusion": {"max_surfels": 4000000, ..., "queue_capacity": 32, ...},
//    "glass": {...}, "loop_closure": {...}}
// Keys are the Options structs' field names. Settings the file leaves out keep their values.
//
// Usage:
//   gf::ReconstructionOptions options;  // throws InputError on any problem in the file:
//   gf::ApplyConfigFile("config.json", &options);
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "pipeline/reconstruction.h"

namespace gf {

// Every setting a config file may set, with its current value.
nlohmann::ordered_json SettingsToJson(const ReconstructionOptions& options);

// Overrides the options with the settings in the JSON text `text`. Throws InputError naming `path`
// and the problem: not JSON (a number beyond a double too), not an object, an unknown setting, a
// value of the wrong type (a fraction for an integer, a number for true/false, an integer beyond
// an int), or values that the options' Check() refuses, named by their place in the tree
// ("fusion.normal_filter_px 30000 is larger than any half-size image (at most 2048)").
// The map's settings given at their place before 2026-12-07 ("fusion": {"fusion": {...}}) are
// read with a warning.
// Every number has an upper bound (acquisition/bounds.h). On a throw the options are unchanged.
void ApplyConfig(const std::string& text, const std::string& path, ReconstructionOptions* options);

// ApplyConfig on the file at `path`; a missing or unreadable file is an InputError too.
void ApplyConfigFile(const std::string& path, ReconstructionOptions* options);

}  // namespace gf
