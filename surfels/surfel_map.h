// The surfel map: the scene as a set of small oriented discs (Keller et al. 2013, ElasticFusion),
// each fused from every measurement that saw it.
//
// A surfel keeps its position and normal in the world frame, its radius, colour, confidence (the
// accumulated weight of the measurements fused into it), the frame that last updated it, the
// sensor readings that landed on it and saw through it, the keyframe it belongs to (to move it
// with a pose correction) and its source: the sensor, a stereo fill, a fill carried from other
// keyframes, or a transparent surface (acquisition/depth.h's DepthSource). A
// surfel is stable once its confidence reaches the threshold of its source (fusion.h); unstable
// surfels are candidates that more measurements must confirm.
//
// Surfels are removed by marking them (confidence < 0) and compacting once enough are marked, so
// indices stay valid within one fusion step.
//
// Thread-safety: none; the fusion stage owns the map.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "acquisition/depth.h"

namespace gf {

struct Surfel {
  Eigen::Vector3f position;  // world frame, metres
  Eigen::Vector3f normal;    // world frame, unit, facing the cameras that saw it
  float radius = 0;          // metres
  float confidence = 0;      // accumulated measurement weight; < 0: removed
  // Sensor pixels around it, over the frames that saw it, whose depth landed on it (within the
  // free-space margin) and that saw through it (farther by more): what tells clear glass, which
  // the sensor both reads and sees through, from an opaque surface (FusionOptions::glass).
  // Both halve together before either overflows.
  uint16_t readings_on = 0, readings_through = 0;
  int32_t last_frame = 0;    // ... that last updated it
  int32_t keyframe = -1;     // the keyframe it belongs to (-1: none yet)
  uint8_t red = 0, green = 0, blue = 0;
  uint8_t source = static_cast<uint8_t>(DepthSource::kSensor);  // DepthSource of its creator
  bool removed() const { return confidence < 0; }
};
static_assert(sizeof(Surfel) <= 48, "a surfel should stay within 48 bytes");

// A surfel of a fill (stereo, COLMAP or carried), not of the sensor's own readings.
inline bool IsFillSource(uint8_t source) {
  return source == static_cast<uint8_t>(DepthSource::kStereo) ||
         source == static_cast<uint8_t>(DepthSource::kColmap) ||
         source == static_cast<uint8_t>(DepthSource::kCarried);
}

// Averages a measurement of weight `weight` into s's position, normal and colour, weighted by s's
// confidence and that weight (s's radius and confidence are the caller's).
inline void BlendInto(Surfel* s, float weight, const Eigen::Vector3f& position,
                      const Eigen::Vector3f& normal, uint8_t red, uint8_t green, uint8_t blue) {
  const float c = s->confidence, to_sum = 1.f / (c + weight);
  const float old_share = c * to_sum, new_share = weight * to_sum;
  s->position = old_share * s->position + new_share * position;
  s->normal = (c * s->normal + weight * normal).normalized();
  // Colour channels are in [0, 255], so adding 0.5 rounds them.
  s->red = static_cast<uint8_t>(old_share * s->red + new_share * red + 0.5f);
  s->green = static_cast<uint8_t>(old_share * s->green + new_share * green + 0.5f);
  s->blue = static_cast<uint8_t>(old_share * s->blue + new_share * blue + 0.5f);
}

class SurfelMap {
 public:
  // Surfels are stored in blocks of kBlock (3 MB): the map grows a block at a time, so a large map
  // is never copied to grow (a vector doubling a 1 M-surfel map copies 48 MB and touches twice
  // that anew) and never needs twice its size while it grows. Surfels i and j share a block when
  // i / kBlock == j / kBlock, and lie one after the other there.
  static constexpr int kBlockBits = 16;
  static constexpr size_t kBlock = size_t{1} << kBlockBits, kBlockMask = kBlock - 1;

  SurfelMap() = default;
  SurfelMap(const SurfelMap& other) { *this = other; }
  SurfelMap& operator=(const SurfelMap& other);
  // A map moved from is empty.
  SurfelMap(SurfelMap&& other) noexcept { *this = std::move(other); }
  SurfelMap& operator=(SurfelMap&& other) noexcept {
    if (this == &other) return *this;
    blocks_ = std::move(other.blocks_);
    other.blocks_.clear();
    size_ = std::exchange(other.size_, 0);
    removed_ = std::exchange(other.removed_, 0);
    first_removed_ = std::exchange(other.first_removed_, kNone);
    return *this;
  }
  size_t size() const { return size_; }  // including surfels marked removed
  size_t live() const { return size_ - removed_; }
  const Surfel& operator[](size_t i) const { return blocks_[i >> kBlockBits][i & kBlockMask]; }
  Surfel& operator[](size_t i) { return blocks_[i >> kBlockBits][i & kBlockMask]; }
  // A copy of every surfel (removed ones too), in map order.
  std::vector<Surfel> ToVector() const;

  // Adds s at the end (one marked removed counts as removed, as Remove would count it).
  void Add(const Surfel& s) {
    if (size_ == blocks_.size() * kBlock) blocks_.push_back(std::make_unique<Surfel[]>(kBlock));
    if (s.removed()) {
      ++removed_;
      first_removed_ = std::min(first_removed_, size_);
    }
    (*this)[size_++] = s;
  }
  void Remove(size_t i) {
    if (!(*this)[i].removed()) {
      (*this)[i].confidence = -1;
      ++removed_;
      first_removed_ = std::min(first_removed_, i);
    }
  }
  // Drops the surfels marked removed (keeps order) when they are more than `share` of the surfels
  // from the first removed one on: those that compaction moves. Its cost is then bounded by
  // 1 / share moves per removal, however large the map (removals are mostly of recent surfels, at
  // the end). Returns the first index whose surfel changed (size() when none did).
  size_t Compact(double share = 0.1);
  void Clear();
  // Bytes held (whole blocks).
  size_t MemoryBytes() const { return blocks_.size() * kBlock * sizeof(Surfel); }

 private:
  static constexpr size_t kNone = ~size_t{0};
  std::vector<std::unique_ptr<Surfel[]>> blocks_;
  size_t size_ = 0;
  size_t removed_ = 0;
  size_t first_removed_ = kNone;  // the lowest index marked removed (kNone: none)
};

}  // namespace gf
