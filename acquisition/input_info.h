// What an input holds, as JSON (`glassfusion info INPUT` prints it; DESIGN.md: source kind,
// frames, size, intrinsics, depth convention, hole fraction). Reads every depth frame for holes.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "acquisition/frame_source.h"

namespace gf {

// progress(done, total) is called after each frame. Throws InputError on bad input.
nlohmann::ordered_json InputInfo(const std::string& input, FrameSourceOptions options,
                                 const std::function<void(int done, int total)>& progress = {});

}  // namespace gf
