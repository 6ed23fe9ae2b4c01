// `glassfusion demo`: the built-in demonstration behind `make demo`.
//
// Current scope: the reconstruction stages are not built yet, so the demo summarises every dataset
// folder it can read (frames, size, depth convention, hole fractions: the holes GlassFusion exists
// to fill) into OUT/report.json and OUT/report.html. It grows with the pipeline.
#pragma once

#include <string>

namespace gf {

// data_dir: folder of dataset folders; "" = ../shared/datasets relative to the working directory.
void RunDemo(const std::string& out_dir, const std::string& data_dir);

}  // namespace gf
