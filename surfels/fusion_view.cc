// The map seen from a camera: culling by chunks, the projected index map, the rendered depth.
#include <algorithm>
#include <atomic>
#include <cstring>
#include <limits>
#include <opencv2/core/utility.hpp>

#include "surfels/fusion.h"  // NOLINT: the class's second source file

namespace gf {
namespace {

// Packs a positive depth and a surfel index so that the smaller value is the nearer surfel.
uint64_t Pack(float z, uint32_t index) {
  uint32_t bits;
  std::memcpy(&bits, &z, sizeof(bits));  // positive floats order as their bits do
  return (static_cast<uint64_t>(bits) << 32) | index;
}

}  // namespace

void SurfelFusion::RefreshChunk(size_t c) {
  Chunk& chunk = chunks_[c];
  if (!chunk.dirty) return;
  chunk.lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());  // empty
  chunk.hi = -chunk.lo;
  chunk.largest = 0;
  const size_t end = std::min(map_.size(), (c + 1) * kChunk);
  for (size_t i = c * kChunk; i < end; ++i)
    if (!map_[i].removed()) chunk.Include(map_[i]);
  chunk.dirty = false;
}

void SurfelFusion::SettleChunks() {
  const size_t needed = (map_.size() + kChunk - 1) / kChunk;
  if (chunks_.size() != needed) chunks_.resize(needed);
  for (size_t c = 0; c < chunks_.size(); ++c)
    if (chunks_[c].dirty) RefreshChunk(c);
}

bool SurfelFusion::ChunkVisible(size_t c, const SE3& camera_from_world) const {
  const Chunk& chunk = chunks_[c];
  if (chunk.lo.x() > chunk.hi.x()) return false;  // all removed
  const Eigen::Vector3f centre = 0.5f * (chunk.lo + chunk.hi);
  const Eigen::Vector3f q = (camera_from_world * centre.cast<double>()).cast<float>();
  const float r = 0.5f * (chunk.hi - chunk.lo).norm() + chunk.largest;
  if (q.z() + r < options_.min_depth_m * 0.5) return false;
  // Outside one of the four planes through the camera centre and the image's edges.
  // Signed distance of the centre beyond the plane a = slope * z (a: x or y, or their negatives).
  auto beyond = [&](float a, float slope) {
    return (a - slope * q.z()) / std::sqrt(1.f + slope * slope) > r;
  };
  if (beyond(q.x(), view_x_[1]) || beyond(-q.x(), -view_x_[0])) return false;
  if (beyond(q.y(), view_y_[1]) || beyond(-q.y(), -view_y_[0])) return false;
  return true;
}

void SurfelFusion::ProjectMap(const SE3& camera_from_world) {
  std::fill(index_map_.begin(), index_map_.end(), kEmpty);
  chunks_.resize((map_.size() + kChunk - 1) / kChunk);
  const int chunks = static_cast<int>(chunks_.size());
  // The chunks in view, and where each one's entries start (entries: the surfels of the chunks
  // in view, in map order; the per-surfel work of this step runs over them only).
  std::vector<uint8_t>& in_view = in_view_;
  in_view.resize(chunks);
  cv::parallel_for_(cv::Range(0, chunks), [&](const cv::Range& range) {
    for (int c = range.start; c < range.end; ++c) {
      RefreshChunk(c);
      in_view[c] = ChunkVisible(c, camera_from_world);
    }
  });
  entry_offset_.resize(chunks);
  size_t entries = 0;
  for (int c = 0; c < chunks; ++c) {
    entry_offset_[c] = entries;
    if (in_view[c]) entries += std::min(map_.size(), (c + 1) * kChunk) - c * kChunk;
  }
  visible_.resize(entries);
  in_camera_.resize(entries);
  normal_radius_.resize(entries);
  pixel_of_.assign(entries, -1);
  entry_flags_.assign(entries, 0);
  camera_rotation_ = camera_from_world.RotationMatrix().cast<float>();
  ProjectEntries(camera_from_world);
  NearestPerPixel();
}

void SurfelFusion::ProjectEntries(const SE3& camera_from_world) {
  const int chunks = static_cast<int>(chunks_.size());
  const std::vector<uint8_t>& in_view = in_view_;
  const std::vector<size_t>& offset = entry_offset_;
  const Eigen::Matrix3f rotation = camera_from_world.RotationMatrix().cast<float>();
  const Eigen::Vector3f translation = camera_from_world.translation().cast<float>();
  // Each entry's position in the camera and its pixel, in entry order.
  cv::parallel_for_(cv::Range(0, chunks), [&](const cv::Range& range) {
    // Camera::ProjectDistorted in float, inlined: this runs for every surfel in view. Every
    // constant is a local, and the outputs are written through local pointers: the compiler may
    // then keep them in registers (stores through the arrays could alias captured references).
    const Eigen::Matrix3f r = rotation;
    const Eigen::Vector3f t = translation;
    const int width = camera_.width, height = camera_.height;
    const float fx = camera_.fx, fy = camera_.fy, cx = camera_.cx, cy = camera_.cy;
    const LensModel<float> lens(camera_.distortion);
    const float near = static_cast<float>(options_.min_depth_m * 0.5);
    const double stable_confidence = options_.stable_confidence,
                 fill_stable_confidence = options_.fill_stable_confidence,
                 glass_stable_confidence = options_.glass.stable_confidence;
    // Unstable surfels last updated before these frames go stale at this step's cleanup unless a
    // pixel updates them (CleanUp's stale test, for a time step's frame_).
    const int sensor_stale_before = frame_ - options_.unstable_frames,
              fill_stale_before = frame_ - options_.fill_unstable_frames;
    uint32_t* const visible = visible_.data();
    uint8_t* const flags = entry_flags_.data();
    Eigen::Vector4f* const normal_radius = normal_radius_.data();
    Eigen::Vector3f* const in_camera = in_camera_.data();
    int32_t* const pixel_of = pixel_of_.data();
    for (int c = range.start; c < range.end; ++c) {
      if (!in_view[c]) continue;
      const size_t first = c * kChunk, end = std::min(map_.size(), first + kChunk);
      const Surfel* const chunk = &map_[first];  // a chunk lies within one block of the map
      for (size_t i = first; i < end; ++i) {
        const size_t e = offset[c] + (i - first);
        visible[e] = static_cast<uint32_t>(i);
        const Surfel& s = chunk[i - first];
        if (s.removed()) continue;
        // IsStable, with the thresholds in locals.
        const bool sensor = s.source == static_cast<uint8_t>(DepthSource::kSensor);
        const bool transparent = s.source == static_cast<uint8_t>(DepthSource::kTransparent);
        const bool stable =
            s.confidence >= (sensor        ? stable_confidence
                             : transparent ? glass_stable_confidence
                                           : fill_stable_confidence);
        if (!stable &&
            s.last_frame < (sensor || transparent ? sensor_stale_before : fill_stale_before))
          flags[e] = kMayGoStale;
        normal_radius[e] << s.normal, s.radius;
        const Eigen::Vector3f q = r * s.position + t;
        in_camera[e] = q;
        if (q.z() < near) continue;
        const float to_plane = 1.f / q.z();
        float a, b;
        lens.Distort(q.x() * to_plane, q.y() * to_plane, &a, &b);
        const float u = fx * a + cx, v = fy * b + cy;
        // Nearest pixel (truncating u + 0.5 rounds it for u >= -0.5; std::lround and std::floor
        // are library calls on baseline x86-64, and this loop runs per surfel in view).
        // The upper bounds keep the conversion defined (a surfel near the camera and far outside
        // the view can land anywhere); the pixel test after it catches u + 0.5 rounding up.
        if (!(u >= -0.5f && v >= -0.5f && u < width - 0.5f && v < height - 0.5f)) continue;
        const int x = static_cast<int>(u + 0.5f), y = static_cast<int>(v + 0.5f);
        if (x < 0 || y < 0 || x >= width || y >= height) continue;
        pixel_of[e] = y * width + x;
      }
    }
  });
}

void SurfelFusion::NearestPerPixel() {
  const int entries = static_cast<int>(visible_.size());
  // The nearest entry per pixel. Map order is not image order, so the index map (larger than a
  // core's cache) is read at random: the cell kPrefetch entries ahead is fetched early.
  // Depth and entry are packed into one 64-bit word, so that the nearest is an atomic minimum when
  // this runs in parallel (a plain one on a single thread: a locked compare-and-swap per surfel
  // costs more than the rest of its projection).
  auto* cells = reinterpret_cast<std::atomic<uint64_t>*>(index_map_.data());
  static_assert(sizeof(std::atomic<uint64_t>) == sizeof(uint64_t), "atomic words");
  const bool serial = cv::getNumThreads() <= 1;
  cv::parallel_for_(cv::Range(0, entries), [&](const cv::Range& range) {
    for (int e = range.start; e < range.end; ++e) {
      if (e + kPrefetch < range.end && pixel_of_[e + kPrefetch] >= 0)
        __builtin_prefetch(&index_map_[pixel_of_[e + kPrefetch]], 1);
      const int pixel = pixel_of_[e];
      if (pixel < 0) continue;
      const uint64_t packed = Pack(in_camera_[e].z(), static_cast<uint32_t>(e));
      if (serial) {
        index_map_[pixel] = std::min(index_map_[pixel], packed);
        continue;
      }
      uint64_t old = cells[pixel].load(std::memory_order_relaxed);
      while (packed < old &&
             !cells[pixel].compare_exchange_weak(old, packed, std::memory_order_relaxed)) {
      }
    }
  });
  // Each pixel's front entry, copied into pixel order (front_ is read only where index_map_ is
  // not empty), its normal turned into the camera.
  const Eigen::Matrix3f rotation = camera_rotation_;
  cv::parallel_for_(cv::Range(0, entries), [&](const cv::Range& range) {
    for (int e = range.start; e < range.end; ++e) {
      if (e + kPrefetch < range.end && pixel_of_[e + kPrefetch] >= 0)
        __builtin_prefetch(&index_map_[pixel_of_[e + kPrefetch]]);
      const int pixel = pixel_of_[e];
      if (pixel < 0 || CellEntry(index_map_[pixel]) != static_cast<uint32_t>(e)) continue;
      front_[pixel] = {in_camera_[e].x(), in_camera_[e].y(), rotation * normal_radius_[e].head<3>(),
                       normal_radius_[e].w()};
    }
  });
}

template <typename Visit>
void SurfelFusion::ForEachSplatPixel(const SE3& world_from_camera, Visit visit) {
  const SE3 camera_from_world = world_from_camera.Inverse();
  SettleChunks();  // (writes nothing when settled: renders may then run at once)
  const Eigen::Matrix3f r = camera_from_world.RotationMatrix().cast<float>();
  const Eigen::Vector3f t = camera_from_world.translation().cast<float>();
  const float focal = static_cast<float>(0.5 * (camera_.fx + camera_.fy));
  constexpr int kMaxSplat = 4;  // pixels
  for (size_t c = 0; c < chunks_.size(); ++c) {
    if (!ChunkVisible(c, camera_from_world)) continue;
    const size_t end = std::min(map_.size(), (c + 1) * kChunk);
    for (size_t i = c * kChunk; i < end; ++i) {
      const Surfel& s = map_[i];
      if (!IsStable(s)) continue;
      const Eigen::Vector3f q = r * s.position + t;
      // A fill's disc faces the camera: its normal comes from stereo depth, whose errors of a few
      // per cent over a few pixels tilt it far more than the sensor's (on punched TUM frames a
      // fill surfel's normal is a median 33 degrees off the nearest sensor surfel's within 1 cm,
      // a sensor surfel's 2 degrees), and a disc tilted that far covers a sliver of its pixels.
      const Eigen::Vector3f normal = r * s.normal;
      const Eigen::Vector3f n = IsFillSource(s.source) ? Eigen::Vector3f(-q.normalized()) : normal;
      if (q.z() < options_.min_depth_m) continue;
      const float n_dot_q = n.dot(q);
      const Eigen::Vector2d uv = camera_.ProjectDistorted(q.cast<double>());
      // Beyond the image by more than a splat, it draws nothing (and the conversion below stays
      // defined).
      if (!(uv.x() >= -0.5 && uv.y() >= -0.5 && uv.x() < camera_.width + kMaxSplat &&
            uv.y() < camera_.height + kMaxSplat))
        continue;
      const int x0 = static_cast<int>(uv.x() + 0.5), y0 = static_cast<int>(uv.y() + 0.5);
      const int radius = std::min(kMaxSplat, static_cast<int>(s.radius * focal / q.z()));
      for (int y = std::max(0, y0 - radius); y <= std::min(camera_.height - 1, y0 + radius); ++y)
        for (int x = std::max(0, x0 - radius); x <= std::min(camera_.width - 1, x0 + radius); ++x) {
          // Where the pixel's ray meets the surfel's disc (an oriented splat: a disc drawn at
          // one depth would bias slanted surfaces towards the camera, nearest first).
          const cv::Vec2f& ray = rays_.at<cv::Vec2f>(y, x);
          const Eigen::Vector3f dir(ray[0], ray[1], 1.f);
          const float along = n.dot(dir);
          if (std::abs(along) < 1e-3f) continue;
          const float z = n_dot_q / along;
          if (!(z > 0) || (dir * z - q).squaredNorm() > s.radius * s.radius) continue;
          visit(s, normal, dir, x, y, z);
        }
    }
  }
}

cv::Mat SurfelFusion::RenderDepth(const SE3& world_from_camera, cv::Mat* front_source) {
  cv::Mat depth = cv::Mat::zeros(camera_.height, camera_.width, CV_32FC1);
  cv::Mat source = cv::Mat::zeros(depth.size(), CV_8UC1);
  ForEachSplatPixel(world_from_camera, [&](const Surfel& s, const Eigen::Vector3f&,
                                           const Eigen::Vector3f&, int x, int y, float z) {
    float& d = depth.at<float>(y, x);
    if (d == 0.f || z < d) {
      d = z;
      source.at<uint8_t>(y, x) = s.source;
    }
  });
  if (front_source) *front_source = source;
  return depth;
}

MapView SurfelFusion::RenderView(const SE3& world_from_camera, double support_margin) {
  MapView view;
  view.depth = cv::Mat::zeros(camera_.height, camera_.width, CV_32FC1);
  view.source = cv::Mat::zeros(view.depth.size(), CV_8UC1);
  view.facing = cv::Mat::zeros(view.depth.size(), CV_32FC1);
  view.support = cv::Mat::zeros(view.depth.size(), CV_32FC1);
  // The nearest surfel per pixel, with how squarely its stored normal faces the camera.
  ForEachSplatPixel(world_from_camera, [&](const Surfel& s, const Eigen::Vector3f& normal,
                                           const Eigen::Vector3f& dir, int x, int y, float z) {
    float& d = view.depth.at<float>(y, x);
    if (d == 0.f || z < d) {
      d = z;
      view.source.at<uint8_t>(y, x) = s.source;
      view.facing.at<float>(y, x) = -normal.dot(dir) / dir.norm();
    }
  });
  // Then the confidence of every surfel on that surface (within support_margin of its depth).
  const float margin = static_cast<float>(support_margin);
  ForEachSplatPixel(world_from_camera, [&](const Surfel& s, const Eigen::Vector3f&,
                                           const Eigen::Vector3f&, int x, int y, float z) {
    const float d = view.depth.at<float>(y, x);
    if (z <= d * (1.f + margin)) view.support.at<float>(y, x) += s.confidence;
  });
  return view;
}

}  // namespace gf
