// `glassfusion bench INPUT --fusion`: the surfel fusion's time per frame on one core and on two,
// on the input's frames with our tracked poses, then with the map grown to about a million surfels
// (copies of it placed out of view, as the rest of a room would be) to show what the map's size
// costs. Also bytes per surfel and the map's memory.
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/trajectory.h"
#include "surfels/fusion.h"

namespace gf {

nlohmann::ordered_json BenchFusion(const std::vector<RgbdFrame>& frames, const Trajectory& tracked,
                                   const Camera& camera, const FusionOptions& options,
                                   size_t large_map_surfels = 1000000);

}  // namespace gf
