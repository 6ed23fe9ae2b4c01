// Small statistics helpers shared by the modules (header only, no state).
#pragma once

#include <algorithm>
#include <vector>

namespace gf {

// The median (upper median for even sizes) of `values`, or `if_empty` when there are none.
template <typename T>
T Median(std::vector<T> values, T if_empty = T(0)) {
  if (values.empty()) return if_empty;
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

}  // namespace gf
