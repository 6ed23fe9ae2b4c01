#include "acquisition/associate.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "acquisition/errors.h"

namespace gf {

std::vector<std::pair<size_t, size_t>> AssociateTimestamps(const std::vector<double>& a,
                                                           const std::vector<double>& b,
                                                           double max_dt) {
  // Candidate pairs within the window (b is sorted, so a binary search bounds each a's range),
  // then greedy by increasing time difference so that each frame is used at most once.
  struct Candidate {
    double dt;
    size_t i, j;
  };
  std::vector<Candidate> candidates;
  for (size_t i = 0; i < a.size(); ++i) {
    auto lo = std::lower_bound(b.begin(), b.end(), a[i] - max_dt);
    for (auto it = lo; it != b.end() && *it <= a[i] + max_dt; ++it) {
      const double dt = std::abs(*it - a[i]);
      if (dt < max_dt) candidates.push_back({dt, i, static_cast<size_t>(it - b.begin())});
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& x, const Candidate& y) { return x.dt < y.dt; });
  std::vector<bool> used_a(a.size(), false), used_b(b.size(), false);
  std::vector<std::pair<size_t, size_t>> pairs;
  for (const Candidate& c : candidates) {
    if (used_a[c.i] || used_b[c.j]) continue;
    used_a[c.i] = used_b[c.j] = true;
    pairs.emplace_back(c.i, c.j);
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

namespace {

std::string Seconds(double s) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.3f s", s);
  return text;
}

}  // namespace

std::vector<std::pair<size_t, size_t>> PairRecordedStreams(const std::vector<double>& depth_s,
                                                           const std::vector<double>& color_s,
                                                           double max_dt_s,
                                                           const std::string& where) {
  if (depth_s.empty()) throw InputError(where, "no depth frames");
  if (color_s.empty()) throw InputError(where, "no colour frames");
  // Pair in time order, then keep the pairs in depth (file) order.
  auto order = [](const std::vector<double>& t) {
    std::vector<size_t> o(t.size());
    std::iota(o.begin(), o.end(), 0);
    std::stable_sort(o.begin(), o.end(), [&](size_t a, size_t b) { return t[a] < t[b]; });
    return o;
  };
  const std::vector<size_t> od = order(depth_s), oc = order(color_s);
  std::vector<double> td, tc;
  for (size_t i : od) td.push_back(depth_s[i]);
  for (size_t i : oc) tc.push_back(color_s[i]);
  // A colour frame is up to half a frame period from the nearest depth frame.
  std::vector<double> intervals;
  for (size_t i = 1; i < td.size(); ++i) intervals.push_back(td[i] - td[i - 1]);
  double window = max_dt_s;
  if (!intervals.empty()) {
    std::nth_element(intervals.begin(), intervals.begin() + intervals.size() / 2,
                     intervals.end());
    window = std::max(window, 0.5 * intervals[intervals.size() / 2]);
  }
  std::vector<std::pair<size_t, size_t>> pairs;
  for (const auto& [i, j] : AssociateTimestamps(td, tc, window)) pairs.emplace_back(od[i], oc[j]);
  std::sort(pairs.begin(), pairs.end());
  if (pairs.empty())
    throw InputError(where, "no depth frame has a colour frame within " + Seconds(window) +
                                " (depth times " + Seconds(td.front()) + " to " +
                                Seconds(td.back()) + ", colour " + Seconds(tc.front()) + " to " +
                                Seconds(tc.back()) + ")");
  if (pairs.size() < depth_s.size())
    spdlog::warn("{}: {} of {} depth frames have no colour frame within {}; left out", where,
                 depth_s.size() - pairs.size(), depth_s.size(), Seconds(window));
  return pairs;
}

}  // namespace gf
