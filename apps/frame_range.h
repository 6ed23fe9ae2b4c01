// --frames, the frame range every command takes.
#pragma once

#include <string>

namespace gf {

// --frames, the same in every command: "A:B" frames A to B-1, "A:" from A, ":B" or "B" the first
// B (whole non-negative numbers). Throws InputError for anything else ("", ":", "1e3:2000", "5:3",
// "a:b"): the whole capture is had by leaving --frames out.
void ParseFrameRange(const std::string& range, int* first, int* end);
// --frames of a command that makes frames from 0 (synth, capture, demo): "N" or "0:N" -> N.
int FrameCountOf(const std::string& range, const std::string& command);

}  // namespace gf
