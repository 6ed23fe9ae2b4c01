// The surfels of a map that pass a test, bucketed in cells of a gap's size, for walks from surfel
// to surfel across gaps of at most that size (the objects of surfels/revolution.h).
//
// No threads, no I/O.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "surfels/surfel_map.h"

namespace gf {

// The surfels of a map that pass a test, in cells of `gap` metres, for walks from surfel to
// surfel within `gap` of one another.
class SurfelGrid {
 public:
  template <typename Keep>
  SurfelGrid(const std::vector<Surfel>& map, double gap, Keep keep)
      : map_(map), gap_(gap), gap2_(static_cast<float>(gap * gap)) {
    for (size_t i = 0; i < map.size(); ++i)
      if (!map[i].removed() && keep(map[i])) {
        cells_[Key(Cell(map[i].position))].push_back(static_cast<int>(i));
        members_.push_back(static_cast<int>(i));
      }
  }
  const std::vector<int>& members() const { return members_; }  // in map order

  // Extends `group` (surfels of the grid) breadth first with every surfel of the grid within gap
  // of one of its surfels that `admit` accepts and `seen` does not hold, marking them seen.
  template <typename Admit>
  void Walk(std::vector<int>* group, std::vector<bool>* seen, Admit admit) const {
    for (size_t next = 0; next < group->size(); ++next) {
      const Eigen::Vector3f p = map_[(*group)[next]].position;
      const Eigen::Vector3i c = Cell(p);
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const auto it = cells_.find(Key(c + Eigen::Vector3i(dx, dy, dz)));
            if (it == cells_.end()) continue;
            for (int j : it->second)
              if (!(*seen)[j] && (map_[j].position - p).squaredNorm() <= gap2_ && admit(j)) {
                (*seen)[j] = true;
                group->push_back(j);
              }
          }
    }
    std::sort(group->begin(), group->end());
  }

 private:
  Eigen::Vector3i Cell(const Eigen::Vector3f& p) const {
    return Eigen::Vector3i(static_cast<int>(std::floor(p.x() / gap_)),
                           static_cast<int>(std::floor(p.y() / gap_)),
                           static_cast<int>(std::floor(p.z() / gap_)));
  }
  static int64_t Key(const Eigen::Vector3i& c) {
    return (static_cast<int64_t>(c.x()) * 73856093) ^ (static_cast<int64_t>(c.y()) * 19349663) ^
           (static_cast<int64_t>(c.z()) * 83492791);
  }
  const std::vector<Surfel>& map_;
  double gap_;
  float gap2_;
  std::unordered_map<int64_t, std::vector<int>> cells_;
  std::vector<int> members_;
};

}  // namespace gf
