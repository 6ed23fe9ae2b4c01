#include "apps/frame_range.h"

#include <charconv>

#include "acquisition/errors.h"

namespace gf {

void ParseFrameRange(const std::string& range, int* first, int* end) {
  // An empty range, or ":" with neither end, names no frames: the whole capture is had by leaving
  // --frames out, never by a range that says nothing.
  if (range.empty() || range == ":")
    throw InputError("--frames", "\"" + range + "\" names no frames: give N, A:B or A:");
  const size_t colon = range.find(':');
  // Whole numbers only: "1e3" must not silently read as 1.
  auto number = [&](const std::string& text, int if_empty) {
    if (text.empty()) return if_empty;
    int value = 0;
    const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || ptr != text.data() + text.size() || value < 0)
      throw InputError("--frames", "\"" + range + "\" is not A:B with whole frame numbers");
    return value;
  };
  if (colon == std::string::npos) {  // "N": the first N frames
    *first = 0;
    *end = number(range, -1);
    if (*end <= 0) throw InputError("--frames", "\"" + range + "\" needs N >= 1 frames");
    return;
  }
  *first = number(range.substr(0, colon), 0);
  *end = number(range.substr(colon + 1), -1);
  if (*end >= 0 && *end <= *first)
    throw InputError("--frames", "\"" + range + "\" needs 0 <= A < B");
}

int FrameCountOf(const std::string& range, const std::string& command) {
  int first = 0, end = -1;
  ParseFrameRange(range, &first, &end);
  if (first != 0 || end < 0)
    throw InputError("--frames",
                     command + " starts at frame 0: give N or 0:N, not \"" + range + "\"");
  return end;
}

}  // namespace gf
