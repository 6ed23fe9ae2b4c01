// After a sensor frame: what the sensor contradicts, what nothing confirmed, redundant copies of a
// surface, and the budget.
#include <algorithm>
#include <cmath>
#include <opencv2/core/utility.hpp>

#include "surfels/fusion.h"  // NOLINT: the class's third source file

namespace gf {
namespace {

float Square(float v) { return v * v; }

}  // namespace

void SurfelFusion::CleanUp(const Measurement& m, FusionStats* stats) {
  RemoveSeenThrough(m, stats);
  if (frame_ % options_.merge_copies_every == 0) MergeRedundant(stats);
  // Unstable surfels that nothing confirmed in time: those in view every frame, the whole map
  // every kFullSweep frames (out of view, they cannot be confirmed anyway).
  auto stale = [&](size_t i) {
    const Surfel& s = map_[i];
    if (s.removed() || IsStable(s)) return;
    const bool fill = IsFillSource(s.source);
    const int window = fill ? options_.fill_unstable_frames : options_.unstable_frames;
    if (frame_ - s.last_frame > window) {
      map_.Remove(i);
      ++stats->removed;
    }
  };
  constexpr int kFullSweep = 16;
  if (frame_ % kFullSweep == 0) {
    // Chunks that held no unstable surfel at their last sweep and changed in no way since are
    // skipped: a large settled map costs nothing here.
    chunks_.resize((map_.size() + kChunk - 1) / kChunk);
    for (size_t c = 0; c < chunks_.size(); ++c) {
      if (chunks_[c].settled) continue;
      const size_t end = std::min(map_.size(), (c + 1) * kChunk);
      bool settled = true;
      for (size_t i = c * kChunk; i < end; ++i) {
        stale(i);
        settled &= map_[i].removed() || IsStable(map_[i]);
      }
      chunks_[c].settled = settled;
    }
  } else {
    // Those in view that projection found unstable and old enough, unless a pixel updated them,
    // and those that lost confidence since. The others cannot be stale: merges only add confidence
    // and never make last_frame older, and this step's frame is the one projection compared with.
    for (size_t e = 0; e < visible_.size(); ++e)
      if ((entry_flags_[e] & (kMayGoStale | kUpdated)) == kMayGoStale) stale(visible_[e]);
  }
  KeepWithinBudget(stats);
  CompactMap();
}

void SurfelFusion::CompactMap() {
  // Compaction moves the surfels after the first removed one: only their chunks are new.
  const size_t before = map_.size(), changed = map_.Compact();
  if (changed < before) {
    chunks_.resize(changed / kChunk);
    chunks_.resize((map_.size() + kChunk - 1) / kChunk);
  }
}

namespace {

// Whether the readings edge_px away from (x, y) along the rows, columns and diagonals (eight
// directions, so that an outline's corner is not missed) that lie in the image and have a reading
// are all farther than `beyond` (at least two of them).
bool ThroughAround(const cv::Mat& depth, int x, int y, int edge_px, float beyond) {
  static constexpr int kSides[8][2] = {{1, 0}, {-1, 0}, {0, 1},  {0, -1},
                                       {1, 1}, {-1, 1}, {1, -1}, {-1, -1}};
  int through = 0;
  for (const auto& side : kSides) {
    const int u = x + side[0] * edge_px, v = y + side[1] * edge_px;
    if (u < 0 || v < 0 || u >= depth.cols || v >= depth.rows) continue;
    const float d = depth.at<float>(v, u);
    if (!(d > 0)) continue;
    if (d <= beyond) return false;
    ++through;
  }
  return through >= 2;
}

// Adds readings to a surfel's counts (halving the counts and the readings alike until they fit
// 16 bits) and says whether it is transparent by them (GlassOptions).
bool CountReadings(int on, int through, const GlassOptions& glass, Surfel* s) {
  constexpr int kMaxCount = 65535;
  while (s->readings_on + on > kMaxCount || s->readings_through + through > kMaxCount) {
    s->readings_on /= 2, s->readings_through /= 2;
    on /= 2, through /= 2;
  }
  s->readings_on = static_cast<uint16_t>(s->readings_on + on);
  s->readings_through = static_cast<uint16_t>(s->readings_through + through);
  const int total = s->readings_on + s->readings_through;
  return s->readings_on >= glass.min_readings_on &&
         s->readings_through >= glass.min_through_share * total;
}

}  // namespace

void SurfelFusion::RemoveSeenThrough(const Measurement& m, FusionStats* stats) {
  // The sensor's readings in the 3x3 pixels around each surfel projected into this frame (those
  // created just now were not): on it (within free_space_margin), through it (farther by more),
  // or in front of it (an occluder: neither); for the glass counts, only the pixel and its four
  // neighbours. Free space: a surfel not updated by this frame that
  // the sensor sees through (every reading around it through it, at least five of them) loses
  // confidence, unless it is transparent. With FusionOptions::glass, the readings add to the
  // counts of the sensor's surfels, which decide whether they are transparent.
  const size_t entries = visible_.size();
  std::vector<EntryReadings>& readings = readings_;
  readings.assign(entries, EntryReadings());
  const int width = camera_.width, height = camera_.height;
  const float near = static_cast<float>(1.0 - options_.free_space_margin);
  const float far = static_cast<float>(1.0 + options_.free_space_margin);
  const GlassOptions& glass = options_.glass;
  const uint8_t sensor = static_cast<uint8_t>(DepthSource::kSensor);
  const uint8_t transparent = static_cast<uint8_t>(DepthSource::kTransparent);
  cv::parallel_for_(cv::Range(0, static_cast<int>(entries)), [&](const cv::Range& range) {
    for (int e = range.start; e < range.end; ++e) {
      if (e + kPrefetch < range.end && pixel_of_[e + kPrefetch] >= width &&
          pixel_of_[e + kPrefetch] < (height - 1) * width) {
        const float* d = m.depth.ptr<float>() + pixel_of_[e + kPrefetch];
        __builtin_prefetch(d - width), __builtin_prefetch(d), __builtin_prefetch(d + width);
      }
      const int pixel = pixel_of_[e];  // -1: not projected (removed, or outside the image)
      if (pixel < 0) continue;
      const int x = pixel % width, y = pixel / width;
      if (x < 1 || y < 1 || x + 1 >= width || y + 1 >= height) continue;
      const float z = in_camera_[e].z();
      EntryReadings r;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const float d = m.depth.at<float>(y + dy, x + dx);
          if (!(d > 0)) continue;
          ++r.measured;
          // The glass counts: the pixel and its four neighbours, whose rays pass through its disc.
          const bool counted = dx == 0 || dy == 0;
          r.through += d > z * far;
          r.counted += counted;
          r.counted_on += counted && d >= z * near && d <= z * far;
          r.counted_through += counted && d > z * far;
        }
      // Seen through across its disc and beyond where an edge could have moved, or not at all:
      // where an opaque surface's outline lies near, some of those readings land on it or in
      // front of it.
      if (r.counted_through < r.counted || r.counted < 3 ||
          !ThroughAround(m.depth, x, y, glass.edge_margin_px, z * far))
        r.counted_through = 0;
      r.seen_through =
          !(entry_flags_[e] & kUpdated) && r.measured >= 5 && r.through == r.measured;
      // Entries are distinct surfels: each task writes its own.
      Surfel& s = map_[visible_[e]];
      if (glass.enabled && r.counted_on + r.counted_through > 0 &&
          (s.source == sensor || s.source == transparent)) {
        const uint8_t was = s.source;
        s.source = CountReadings(r.counted_on, r.counted_through, glass, &s) ? transparent : sensor;
        r.turned = s.source != was;
      }
      readings[e] = r;
    }
  });
  ApplyReadings(stats);
}

void SurfelFusion::ApplyReadings(FusionStats* stats) {
  const GlassOptions& glass = options_.glass;
  const uint8_t sensor = static_cast<uint8_t>(DepthSource::kSensor);
  const uint8_t transparent = static_cast<uint8_t>(DepthSource::kTransparent);
  const std::vector<EntryReadings>& readings = readings_;
  for (size_t e = 0; e < readings.size(); ++e) {
    const EntryReadings& r = readings[e];
    const size_t i = visible_[e];
    Surfel& s = map_[i];
    if (r.turned) {
      stats->transparent += s.source == transparent;
      entry_flags_[e] |= kMayGoStale;  // its stable confidence changed
      Touch(i);
    }
    if (!r.seen_through) continue;
    ++stats->contradicted;
    if (s.source == transparent) {
      // Seeing the background through glass is what glass does; glass that the sensor has not
      // read for unstable_frames frames while seeing through it is not there (an object that
      // moved away, or a misplaced surface).
      if (frame_ - s.last_frame > options_.unstable_frames) {
        map_.Remove(i);
        ++stats->removed;
      }
      continue;
    }
    // A stable surface loses confidence; so does, with glass, one that views after the one that
    // made it read (it may be glass that this view sees through); any other goes.
    const bool read_again = glass.enabled && s.readings_on >= glass.min_readings_on;
    const bool stable_sensor = s.source == sensor && (IsStable(s) || read_again);
    const float penalty = static_cast<float>(options_.free_space_penalty);
    if (!stable_sensor || s.confidence - penalty <= 0) {
      // Through the map, not by the penalty: a confidence pushed below zero would read as removed
      // without being counted (nor compacted).
      map_.Remove(i);
      ++stats->removed;
    } else {
      s.confidence -= penalty;
      entry_flags_[e] |= kMayGoStale;  // it may be unstable now
      Touch(i);
    }
  }
}

void SurfelFusion::MergeRedundant(FusionStats* stats) {
  // Two surfels that project into the same 3x3 pixels of the index map and that lie on one surface
  // (depths within free_space_margin of each other, normals within max_normal_angle_deg whatever
  // their facing: a surfel's normal is averaged over its measurements, steadier than one pixel's),
  // with each centre within the other's disc, are copies of one piece
  // of surface (passes with slightly different poses leave them); the hidden one is
  // invisible to association from here on, so keeping both only stacks copies. The less confident
  // one is merged into the other, by the same confidence-weighted average as a measurement; the
  // kept surfel keeps its source (a fill that the sensor's copy confirms stays a fill).
  // Positions are those projected at the start of this step (its merges move them by a fraction
  // of the depth margin).
  FindCopies();
  const std::vector<int32_t>& partner = partner_;
  for (size_t e = 0; e < partner.size(); ++e) {
    if (partner[e] < 0) continue;
    size_t keep_entry = partner[e], drop_entry = e;
    if (map_[visible_[drop_entry]].confidence > map_[visible_[keep_entry]].confidence)
      std::swap(keep_entry, drop_entry);
    const size_t keep = visible_[keep_entry], drop = visible_[drop_entry];
    if (map_[keep].removed() || map_[drop].removed()) continue;  // merged already this step
    Surfel& k = map_[keep];
    const Surfel& d = map_[drop];
    BlendInto(&k, d.confidence, d.position, d.normal, d.red, d.green, d.blue);
    k.radius = std::min(k.radius, d.radius);
    // Two fills of different keyframes on one surface confirm each other (FindCopies has checked
    // their depths; in_camera_ holds both at this step).
    k.confidence = IsFillSource(k.source) && IsFillSource(d.source)
                       ? FillConfidence(k, k.confidence + d.confidence, d.keyframe,
                                        in_camera_[keep_entry].z(), in_camera_[drop_entry].z())
                       : k.confidence + d.confidence;
    CountReadings(d.readings_on, d.readings_through, options_.glass, &k);
    if (d.last_frame > k.last_frame) {  // it moves with the keyframe that saw it last
      k.last_frame = d.last_frame;
      k.keyframe = d.keyframe;
    }
    TouchGeometry(keep);
    map_.Remove(drop);
    ++stats->redundant;
    ++stats->removed;
  }
}

void SurfelFusion::FindCopies() {
  const size_t entries = visible_.size();
  std::vector<int32_t>& partner = partner_;
  partner.assign(entries, -1);
  const float margin = static_cast<float>(options_.free_space_margin);
  const float cos_max = static_cast<float>(std::cos(options_.max_normal_angle_deg * M_PI / 180.0));
  const int width = camera_.width, height = camera_.height;
  // a, b: an entry's position and normal in the camera, and its radius.
  auto copies = [&](const Eigen::Vector3f& qa, const Eigen::Vector3f& na, float ra,
                    const Eigen::Vector3f& qb, const Eigen::Vector3f& nb, float rb) {
    if (std::abs(qa.z() - qb.z()) > margin * qb.z() || na.dot(nb) < cos_max) return false;
    // Each centre within the other's disc (closer than the smaller radius across the ray):
    // denser than any one measurement samples a surface (neighbours on its pixel grid lie a
    // radius or more apart), so copies of one piece of surface.
    const Eigen::Vector2f across = qa.head<2>() * (qb.z() / qa.z()) - qb.head<2>();
    return across.squaredNorm() < Square(std::min(ra, rb));
  };
  // A hidden surfel against the one that hides it.
  cv::parallel_for_(cv::Range(0, static_cast<int>(entries)), [&](const cv::Range& range) {
    for (int e = range.start; e < range.end; ++e) {
      if (e + kPrefetch < range.end && pixel_of_[e + kPrefetch] >= 0) {
        __builtin_prefetch(&index_map_[pixel_of_[e + kPrefetch]]);
        __builtin_prefetch(&front_[pixel_of_[e + kPrefetch]]);
      }
      const int pixel = pixel_of_[e];
      if (pixel < 0) continue;
      const uint64_t cell = index_map_[pixel];
      if (CellEntry(cell) == static_cast<uint32_t>(e)) continue;
      const Front& f = front_[pixel];
      const Eigen::Vector4f& a = normal_radius_[e];
      if (copies(in_camera_[e], camera_rotation_ * a.head<3>(), a.w(), {f.x, f.y, CellDepth(cell)},
                 f.normal, f.radius))
        partner[e] = static_cast<int32_t>(CellEntry(cell));
    }
  });
  // A pixel's front surfel against those of the pixels after it (right, and the three below), so
  // that each pair of pixels is tested once; in pixel order, as the front data are stored.
  cv::parallel_for_(cv::Range(1, height - 2), [&](const cv::Range& range) {
    for (int y = range.start; y < range.end; ++y)
      for (int x = 1; x + 2 < width; ++x) {
        const size_t p = static_cast<size_t>(y) * width + x;
        if (index_map_[p] == kEmpty) continue;
        const Front& f = front_[p];
        const Eigen::Vector3f qf(f.x, f.y, CellDepth(index_map_[p]));
        for (const size_t q : {p + 1, p + width - 1, p + width, p + width + 1}) {
          if (index_map_[q] == kEmpty) continue;
          const Front& g = front_[q];
          if (!copies(qf, f.normal, f.radius, {g.x, g.y, CellDepth(index_map_[q])}, g.normal,
                      g.radius))
            continue;
          partner[CellEntry(index_map_[p])] = static_cast<int32_t>(CellEntry(index_map_[q]));
          break;
        }
      }
  });
}

void SurfelFusion::KeepWithinBudget(FusionStats* stats) {
  const size_t budget = static_cast<size_t>(options_.max_surfels);
  if (map_.live() <= budget) return;
  // Down to 95% of the budget, so that this runs once in many frames: the unstable surfels first
  // (least confident first), then the stable ones seen longest ago.
  const size_t excess = map_.live() - budget + budget / 20;
  std::vector<uint32_t> order;
  order.reserve(map_.live());
  for (size_t i = 0; i < map_.size(); ++i)
    if (!map_[i].removed()) order.push_back(static_cast<uint32_t>(i));
  auto worse = [&](uint32_t i, uint32_t j) {
    const Surfel &a = map_[i], &b = map_[j];
    const bool sa = IsStable(a), sb = IsStable(b);
    if (sa != sb) return !sa;
    if (!sa) return a.confidence < b.confidence;
    return a.last_frame < b.last_frame;
  };
  const size_t n = std::min(excess, order.size());
  std::nth_element(order.begin(), order.begin() + n, order.end(), worse);
  for (size_t k = 0; k < n; ++k) map_.Remove(order[k]);
  stats->over_budget += static_cast<int>(n);
  stats->removed += static_cast<int>(n);
}

}  // namespace gf
