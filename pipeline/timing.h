// How long a stage's steps took, as report.json and bench write it: {"median_ms", "max_ms",
// "count"} (null times when there were none).
#pragma once

#include <algorithm>
#include <nlohmann/json.hpp>
#include <vector>

namespace gf {

inline nlohmann::ordered_json TimingJson(std::vector<double> ms) {
  if (ms.empty()) return {{"median_ms", nullptr}, {"max_ms", nullptr}, {"count", 0}};
  std::sort(ms.begin(), ms.end());
  return {{"median_ms", ms[ms.size() / 2]}, {"max_ms", ms.back()}, {"count", ms.size()}};
}

}  // namespace gf
