#include "surfels/surfel_map.h"

namespace gf {

SurfelMap& SurfelMap::operator=(const SurfelMap& other) {
  if (this == &other) return *this;
  Clear();
  for (size_t i = 0; i < other.size_; ++i) Add(other[i]);  // counts the removed ones
  return *this;
}

std::vector<Surfel> SurfelMap::ToVector() const {
  std::vector<Surfel> out;
  out.reserve(size_);
  for (size_t i = 0; i < size_; ++i) out.push_back((*this)[i]);
  return out;
}

size_t SurfelMap::Compact(double share) {
  if (removed_ == 0 || removed_ < share * (size_ - first_removed_)) return size_;
  const size_t changed = first_removed_;
  size_t kept = changed;
  for (size_t i = changed; i < size_; ++i)
    if (!(*this)[i].removed()) (*this)[kept++] = (*this)[i];
  size_ = kept;
  // Blocks no longer used go, but one spare: a map that shrinks and grows again around a block's
  // edge would otherwise free and allocate it every step.
  blocks_.resize(std::min(blocks_.size(), (size_ + kBlockMask) / kBlock + 1));
  removed_ = 0;
  first_removed_ = kNone;
  return changed;
}

void SurfelMap::Clear() {
  blocks_.clear();
  size_ = removed_ = 0;
  first_removed_ = kNone;
}

}  // namespace gf
