// A run folder read back: what the folder sink (run_sink.h) writes, found through RunLayout's
// names (acquisition/run_layout.h). The reports, compare, the mesh and the benchmark read a
// run's outputs through it; the evaluation (eval/, below pipeline/) reads them through RunLayout.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/run_layout.h"
#include "acquisition/trajectory.h"
#include "pipeline/run_report.h"
#include "surfels/surfel_map.h"

namespace gf {

class RunReader {
 public:
  // dir: a run folder (reconstruct's --out, or compare's with_fill/ or without_fill/).
  explicit RunReader(std::string dir) : layout_(std::move(dir)) {}
  explicit RunReader(RunLayout layout) : layout_(std::move(layout)) {}
  const RunLayout& layout() const { return layout_; }
  const std::string& dir() const { return layout_.dir(); }

  // Whether the run wrote `relative` (RunLayout::kMap, ...): a run without fusion has no map, a
  // run stopped early may lack its trajectory.
  bool Has(const std::string& relative) const;
  // Each throws InputError when its file is absent or unreadable.
  RunReport Report() const;               // report.json
  Trajectory Poses() const;               // trajectory.txt: every frame's world_from_camera
  Camera ImageCamera() const;             // camera.json: the camera of keyframes/
  std::vector<Surfel> Map() const;        // map.ply

 private:
  RunLayout layout_;
};

}  // namespace gf
