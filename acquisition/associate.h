// Pairing the depth and colour frames of a capture by time.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace gf {

// Pairs two sorted timestamp lists one-to-one by nearest time within max_dt (associate.py):
// returns (index_a, index_b) pairs sorted by index_a.
std::vector<std::pair<size_t, size_t>> AssociateTimestamps(const std::vector<double>& a,
                                                           const std::vector<double>& b,
                                                           double max_dt);

// Pairs the frames of a recording's depth and colour streams, which run free of each other:
// depth_s and color_s are their times in seconds in file order (not necessarily sorted). A colour
// frame pairs with the depth frame nearest in time, one to one, within half the depth stream's
// median frame interval (or max_dt_s where that is larger). Returns (depth, colour) indices in
// depth order. Logs how many depth frames found no colour frame; throws InputError naming
// `where` when there are no frames or none pair.
std::vector<std::pair<size_t, size_t>> PairRecordedStreams(const std::vector<double>& depth_s,
                                                           const std::vector<double>& color_s,
                                                           double max_dt_s,
                                                           const std::string& where);

}  // namespace gf
