#include "surfels/fusion.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "acquisition/errors.h"

namespace gf {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

}  // namespace

SurfelFusion::SurfelFusion(const Camera& camera, const FusionOptions& options)
    : camera_(camera), options_(options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  const UndistortedPixels undistorted(camera);
  rays_.create(camera.height, camera.width, CV_32FC2);
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const Eigen::Vector2d r = undistorted.Ray(x, y);
      rays_.at<cv::Vec2f>(y, x) = {static_cast<float>(r.x()), static_cast<float>(r.y())};
    }
  // The rays of the pixels that the half-size depth keeps (the same nearest-pixel resize), for
  // normals: a vertex there is that pixel's ray times its depth.
  cv::Mat half_rays, planes[2];
  cv::resize(rays_, half_rays, {}, 0.5, 0.5, cv::INTER_NEAREST);
  cv::split(half_rays, planes);
  half_ray_x_ = planes[0], half_ray_y_ = planes[1];
  index_map_.assign(static_cast<size_t>(camera.width) * camera.height, kEmpty);
  front_.resize(index_map_.size());
  // A measurement's weight by its pixel's distance r from the image centre, over the half
  // diagonal: exp(-r^2 / (2 sigma^2)).
  radial_weight_.create(camera.height, camera.width, CV_32FC1);
  const double half_diagonal = 0.5 * std::hypot(camera.width, camera.height);
  const double two_sigma2 = 2 * options.confidence_sigma * options.confidence_sigma;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const double r = std::hypot(x - camera.cx, y - camera.cy) / half_diagonal;
      radial_weight_.at<float>(y, x) = static_cast<float>(std::exp(-r * r / two_sigma2));
    }
  // The image's extent in normalised coordinates (over its border rays), for culling.
  view_x_[0] = view_y_[0] = std::numeric_limits<float>::max();
  view_x_[1] = view_y_[1] = -std::numeric_limits<float>::max();
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      if (y > 0 && y + 1 < camera.height && x > 0 && x + 1 < camera.width) continue;
      const cv::Vec2f r = rays_.at<cv::Vec2f>(y, x);
      view_x_[0] = std::min(view_x_[0], r[0]), view_x_[1] = std::max(view_x_[1], r[0]);
      view_y_[0] = std::min(view_y_[0], r[1]), view_y_[1] = std::max(view_y_[1], r[1]);
    }
}

FusionStats SurfelFusion::FuseFrame(const RgbdFrame& frame, const SE3& world_from_camera,
                                    int keyframe) {
  GF_CHECK(frame.depth.type() == CV_32FC1 && frame.depth.cols == camera_.width &&
               frame.depth.rows == camera_.height,
           "fusion: depth must be CV_32F of the camera's size");
  ++frame_;
  const cv::Mat none;
  return Fuse({frame.depth, none, none, 1.0, DepthSource::kSensor, frame.color, world_from_camera,
               keyframe, true, options_.pixel_step, frame_ % options_.pixel_step});
}

FusionStats SurfelFusion::FuseFill(const RgbdFrame& frame, const cv::Mat& filled_depth,
                                   const cv::Mat& fill_mask, const cv::Mat& confidence,
                                   DepthSource source, const SE3& world_from_camera, int keyframe) {
  GF_CHECK(
      filled_depth.type() == CV_32FC1 && fill_mask.type() == CV_8UC1 &&
          confidence.type() == CV_32FC1 && filled_depth.cols == camera_.width &&
          filled_depth.rows == camera_.height && fill_mask.size() == filled_depth.size() &&
          confidence.size() == filled_depth.size(),
      "fusion: a fill needs CV_32F depth and confidence and a CV_8U mask of the camera's size");
  ++fills_;
  return Fuse({filled_depth, fill_mask, confidence, options_.fill_weight, source, frame.color,
               world_from_camera, keyframe, false, options_.fill_pixel_step,
               fills_ % options_.fill_pixel_step});
}

// What stays the same over one measurement's pixels.
struct SurfelFusion::StepConstants {
  const cv::Mat* smooth_half;  // the depth at half size, bilateral-filtered (for normals)
  float cos_max, min_facing, focal, min_z, max_z, max_step, gap;
  bool has_color;
};

FusionStats SurfelFusion::Fuse(const Measurement& m) {
  const auto start = std::chrono::steady_clock::now();
  FusionStats stats;
  ProjectMap(m.world_from_camera.Inverse());
  const int width = camera_.width, height = camera_.height, step = m.step;
  StepConstants k;
  k.cos_max = static_cast<float>(std::cos(options_.max_normal_angle_deg * kDegToRad));
  k.focal = static_cast<float>(0.5 * (camera_.fx + camera_.fy));
  k.min_facing = static_cast<float>(options_.normal_test_min_facing);
  k.min_z = static_cast<float>(options_.min_depth_m);
  k.max_z = static_cast<float>(options_.max_depth_m);
  k.max_step = static_cast<float>(options_.max_neighbour_step);
  k.gap = static_cast<float>(options_.max_depth_gap_m);
  k.has_color = m.color.type() == CV_8UC3 && m.color.size() == m.depth.size();
  // Normals (and radii) from the depth smoothed by a bilateral filter, as ElasticFusion does: the
  // sensor's quantised depth makes neighbour differences too noisy for the normal test (at 3 m a
  // Kinect v1 depth step is about 3 cm). The filter runs on the depth at half size (normals span
  // normal_baseline_px either side); positions come from the measured depth.
  cv::resize(m.depth, half_depth_, {}, 0.5, 0.5, cv::INTER_NEAREST);
  cv::bilateralFilter(half_depth_, smooth_half_, options_.normal_filter_px,
                      options_.normal_filter_depth_m, 0.5 * options_.normal_filter_px);
  k.smooth_half = &smooth_half_;
  const int grid_cols = (width - m.grid_offset + step - 1) / step;
  const int grid_rows = (height - m.grid_offset + step - 1) / step;
  std::vector<PixelResult>& results = results_;  // kept between steps: no allocation per step
  results.resize(static_cast<size_t>(grid_cols) * grid_rows);
  cv::parallel_for_(cv::Range(0, grid_rows), [&](const cv::Range& range) {
    // Per thread, kept between rows and steps (OpenCV may hand each row to a task of its own).
    thread_local GridRow normals(0);
    normals.Resize(grid_cols);
    for (int gy = range.start; gy < range.end; ++gy)
      MeasureRow(m, k, m.grid_offset + gy * step, &results[static_cast<size_t>(gy) * grid_cols],
                 &normals);
  });
  Integrate(m, results, &stats);
  if (m.time_step) {
    CleanUp(m, &stats);
  } else if (map_.live() > static_cast<size_t>(options_.max_surfels)) {
    // A fill is no time step (nothing is stale or seen through after it), but its surfels count
    // against the budget as the sensor's do: a map of many fills must stay within max_surfels too.
    KeepWithinBudget(&stats);
    CompactMap();
  }
  stats.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

void SurfelFusion::MeasureRow(const Measurement& m, const StepConstants& k, int y, PixelResult* row,
                              GridRow* grid) const {
  const int width = camera_.width, height = camera_.height, step = m.step;
  const int grid_cols = (width - m.grid_offset + step - 1) / step;
  for (int gx = 0; gx < grid_cols; ++gx) {
    row[gx].valid = false;  // a valid pixel's other fields are all set below
    row[gx].match = -1;
  }
  // A pixel needs its four neighbours (for the neighbour test) and the pixels normal_baseline_px
  // away (for its normal) inside the image.
  const int b = options_.normal_baseline_px, border = std::max(1, b);
  if (y < border || y + border >= height) return;
  // Rows and constants as locals: the loop's stores to the results could otherwise alias them.
  const float *depth = m.depth.ptr<float>(y), *depth_up = m.depth.ptr<float>(y - 1),
              *depth_down = m.depth.ptr<float>(y + 1);
  const uint8_t* mask = m.mask.empty() ? nullptr : m.mask.ptr<uint8_t>(y);
  const float* weight = m.weight.empty() ? nullptr : m.weight.ptr<float>(y);
  const cv::Vec3b* color = k.has_color ? m.color.ptr<cv::Vec3b>(y) : nullptr;
  const cv::Vec2f* ray = rays_.ptr<cv::Vec2f>(y);
  const float* radial = radial_weight_.ptr<float>(y);
  const float min_z = k.min_z, max_z = k.max_z, max_step = k.max_step, focal = k.focal;
  const float weight_scale = static_cast<float>(m.weight_scale);
  const DepthSource source = m.source;
  // Grid columns whose pixel lies border or more inside the image (x = grid_offset + step gx).
  const int first = std::max(0, (border - m.grid_offset + step - 1) / step);
  const int last_x = width - 1 - border;  // (below the offset: no column, as division truncates)
  const int end =
      last_x < m.grid_offset ? 0 : std::min(grid_cols, (last_x - m.grid_offset) / step + 1);
  if (first >= end) return;
  RowNormals(*k.smooth_half, step, m.grid_offset, y, first, end, grid);
  for (int gx = first; gx < end; ++gx) {
    const int x = m.grid_offset + gx * step;
    if (mask && !mask[x]) continue;
    const float z = depth[x];
    if (!(z >= min_z && z <= max_z)) continue;
    // A normal needs all four neighbours on the same surface.
    // (Bitwise, not short-circuit: four compares and no branch each.)
    const float step_z = max_step * z;
    const float left_z = depth[x - 1], right_z = depth[x + 1], up_z = depth_up[x],
                down_z = depth_down[x];
    const bool neighbours = (left_z > 0) & (right_z > 0) & (up_z > 0) & (down_z > 0) &
                            (std::abs(left_z - z) <= step_z) & (std::abs(right_z - z) <= step_z) &
                            (std::abs(up_z - z) <= step_z) & (std::abs(down_z - z) <= step_z);
    if (!neighbours) continue;
    if (!grid->has_normal[gx]) continue;
    PixelResult& res = row[gx];
    res.point = Eigen::Vector3f(ray[x][0] * z, ray[x][1] * z, z);
    const Eigen::Vector3f n(grid->nx[gx], grid->ny[gx], grid->nz[gx]);
    res.normal = n;
    const float head_on = std::sqrt(2.f) * z / focal;
    res.radius = std::min(2.f * head_on, head_on / std::max(std::abs(n.z()), 1e-3f));
    res.weight = radial[x] * (weight ? weight[x] : 1.f) * weight_scale;
    if (!(res.weight > 0)) continue;
    if (color) {
      res.red = color[x][2], res.green = color[x][1], res.blue = color[x][0];
    } else {
      res.red = res.green = res.blue = 0;
    }
    res.source = source;
    res.corroborated = mask && mask[x] == kCorroboratedFill;
    res.valid = true;
    res.match = NearestAlongRay(k, x, y, ray[x], res);
  }
}

namespace {

// The normal from the vertices right - left and down - up, unit and facing the camera (against
// the ray (ray_x, ray_y, 1)); has 0 when the vertices give none (the normal then means nothing).
inline void UnitNormal(float ax, float ay, float az, float bx, float by, float bz, float ray_x,
                       float ray_y, float* nx, float* ny, float* nz, float* has) {
  const float cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx;
  const float norm2 = cx * cx + cy * cy + cz * cz;
  const float inverse = 1.f / std::sqrt(std::max(norm2, 1e-30f));
  const float scale = cx * ray_x + cy * ray_y + cz > 0 ? -inverse : inverse;
  *nx = cx * scale, *ny = cy * scale, *nz = cz * scale;
  *has = norm2 >= 1e-30f ? 1.f : 0.f;  // below, the clamp would leave it short of unit length
}

// RowNormals' loop for the step-2 grid: half-size row j (row), j - h (up), j + h (down) of the
// smoothed depth and of the rays; grid column i is cell i. No two rows overlap (__restrict), and
// nothing branches: the loop vectorises (GCC 12 keeps the __restrict only when this is not
// inlined).
__attribute__((noinline)) void GridNormalsLoop(
    const float* __restrict depth, const float* __restrict depth_up,
    const float* __restrict depth_down, const float* __restrict x_row, const float* __restrict x_up,
    const float* __restrict x_down, const float* __restrict y_row, const float* __restrict y_up,
    const float* __restrict y_down, float* __restrict nx, float* __restrict ny,
    float* __restrict nz, float* __restrict has_normal, int first, int end, int h) {
  for (int i = first; i < end; ++i) {
    const float zr = depth[i + h], zl = depth[i - h], zd = depth_down[i], zu = depth_up[i];
    UnitNormal(x_row[i + h] * zr - x_row[i - h] * zl, y_row[i + h] * zr - y_row[i - h] * zl,
               zr - zl, x_down[i] * zd - x_up[i] * zu, y_down[i] * zd - y_up[i] * zu, zd - zu,
               x_row[i], y_row[i], &nx[i], &ny[i], &nz[i], &has_normal[i]);
  }
}

}  // namespace

void SurfelFusion::RowNormals(const cv::Mat& smooth, int step, int grid_offset, int y, int first,
                              int end, GridRow* grid) const {
  // Pixel x's normal: from the vertices normal_baseline_px (b) either side, at the smoothed
  // half-size depth of cells (x +- b) / 2 and (y +- b) / 2, each on the ray of the pixel that
  // cell's depth came from (half_ray_x_, half_ray_y_).
  const int b = options_.normal_baseline_px, h = b / 2;
  const int last_row = smooth.rows - 1, last_col = smooth.cols - 1;
  const int j = std::min(y / 2, last_row), up = std::min((y - b) / 2, last_row),
            down = std::min((y + b) / 2, last_row);
  const float *depth = smooth.ptr<float>(j), *depth_up = smooth.ptr<float>(up),
              *depth_down = smooth.ptr<float>(down);
  const float *x_row = half_ray_x_.ptr<float>(j), *x_up = half_ray_x_.ptr<float>(up),
              *x_down = half_ray_x_.ptr<float>(down);
  const float *y_row = half_ray_y_.ptr<float>(j), *y_up = half_ray_y_.ptr<float>(up),
              *y_down = half_ray_y_.ptr<float>(down);
  int gx = first;
  // On the step-2 grid with an even baseline, pixel 2i + p has cells i and i +- h, and rows
  // j +- h: the vectorised loop, over the columns where no index needs clamping.
  if (step == 2 && b % 2 == 0 && up == j - h && down == j + h) {
    const int fast_end = std::max(first, std::min(end, last_col - h + 1));
    GridNormalsLoop(depth, depth_up, depth_down, x_row, x_up, x_down, y_row, y_up, y_down,
                    grid->nx.data(), grid->ny.data(), grid->nz.data(), grid->has_normal.data(),
                    first, fast_end, h);
    gx = fast_end;
  }
  for (; gx < end; ++gx) {
    const int x = grid_offset + gx * step;
    const int c = std::min(x / 2, last_col), right = std::min((x + b) / 2, last_col),
              left = std::min((x - b) / 2, last_col);
    const float zr = depth[right], zl = depth[left], zd = depth_down[c], zu = depth_up[c];
    UnitNormal(x_row[right] * zr - x_row[left] * zl, y_row[right] * zr - y_row[left] * zl, zr - zl,
               x_down[c] * zd - x_up[c] * zu, y_down[c] * zd - y_up[c] * zu, zd - zu, x_row[c],
               y_row[c], &grid->nx[gx], &grid->ny[gx], &grid->nz[gx], &grid->has_normal[gx]);
  }
}

int SurfelFusion::NearestAlongRay(const StepConstants& k, int x, int y, const cv::Vec2f& ray,
                                  const PixelResult& res) const {
  // The surfel in the 3x3 index-map window nearest the pixel's ray, within the depth gap along it
  // and, where it faces the camera, with a normal within the angle (both normals in the camera).
  const float z = res.point.z(), cos_max = k.cos_max, min_facing = k.min_facing;
  const float rx = ray[0], ry = ray[1];
  // |z_surfel - z| * |ray| < gap: the distance along the ray.
  const float gap_in_z = k.gap / std::sqrt(1.f + rx * rx + ry * ry);
  const Eigen::Vector3f normal = res.normal;
  float best = std::numeric_limits<float>::max();
  int match = -1;
  const size_t width = camera_.width;
  for (int dy = -1; dy <= 1; ++dy) {
    const size_t centre = (y + dy) * width + x;
    const uint64_t* cells = index_map_.data() + centre;
    const Front* fronts = front_.data() + centre;
    for (int dx = -1; dx <= 1; ++dx) {
      const uint64_t cell = cells[dx];
      if (cell == kEmpty) continue;
      const float qz = CellDepth(cell);
      if (std::abs(qz - z) >= gap_in_z) continue;
      const Front& f = fronts[dx];
      if (f.normal.dot(normal) < cos_max && std::abs(f.normal.z()) >= min_facing) continue;
      // |ray x q|^2 orders as the distance from the ray, ray = (rx, ry, 1).
      const float cx = ry * qz - f.y, cy = f.x - rx * qz, cz = rx * f.y - ry * f.x;
      const float dist = cx * cx + cy * cy + cz * cz;
      if (dist < best) {
        best = dist;
        match = static_cast<int>(CellEntry(cell));
      }
    }
  }
  return match;
}

void SurfelFusion::Integrate(const Measurement& m, const std::vector<PixelResult>& results,
                             FusionStats* stats) {
  // Merge and create, one pixel after the other (several pixels may update one surfel).
  const Eigen::Matrix3f r_wc = m.world_from_camera.RotationMatrix().cast<float>();
  const Eigen::Vector3f t_wc = m.world_from_camera.translation().cast<float>();
  const bool fill = m.source != DepthSource::kSensor;
  // Pixel order is not map order: the surfel kPrefetch pixels ahead is fetched early.
  for (size_t j = 0; j < results.size(); ++j) {
    if (j + kPrefetch < results.size() && results[j + kPrefetch].match >= 0)
      __builtin_prefetch(&map_[visible_[results[j + kPrefetch].match]], 1);
    const PixelResult& res = results[j];
    if (!res.valid) continue;
    ++stats->measured;
    const Eigen::Vector3f p = r_wc * res.point + t_wc, n = r_wc * res.normal;
    if (res.match >= 0) {
      const size_t index = visible_[res.match];
      entry_flags_[res.match] |= kUpdated;
      Surfel& s = map_[index];
      const float c = s.confidence, a = res.weight, sum = c + a;
      if (res.radius < options_.max_radius_ratio * s.radius) {
        BlendInto(&s, a, p, n, res.red, res.green, res.blue);
        s.radius = (c * s.radius + a * res.radius) / sum;
      }
      s.confidence =
          fill && IsFillSource(s.source)
              ? WithCorroboration(
                    FillConfidence(s, sum, m.keyframe, in_camera_[res.match].z(), res.point.z()),
                    res.corroborated)
              : sum;
      s.last_frame = frame_;
      s.keyframe = m.keyframe;
      TouchGeometry(index);
      ++stats->merged;
    } else {
      Surfel s;
      s.position = p;
      s.normal = n;
      s.radius = res.radius;
      s.confidence = WithCorroboration(res.weight, res.corroborated);
      s.last_frame = frame_;
      s.keyframe = m.keyframe;
      s.red = res.red, s.green = res.green, s.blue = res.blue;
      s.source = static_cast<uint8_t>(res.source);
      map_.Add(s);
      if (chunks_.size() * kChunk < map_.size()) chunks_.emplace_back();
      TouchGeometry(map_.size() - 1);
      ++stats->created;
    }
  }
}

float SurfelFusion::FillConfidence(const Surfel& s, float confidence, int other_keyframe, float z,
                                   float other_z) const {
  if (!options_.confirm_fills_across_keyframes || s.keyframe == other_keyframe ||
      !(std::abs(z - other_z) <= options_.free_space_margin * std::max(z, other_z)))
    return confidence;
  return std::max(confidence, static_cast<float>(options_.fill_stable_confidence));
}

float SurfelFusion::WithCorroboration(float confidence, bool corroborated) const {
  return corroborated && options_.confirm_corroborated_fills
             ? std::max(confidence, static_cast<float>(options_.fill_stable_confidence))
             : confidence;
}

float SurfelFusion::StableConfidence(uint8_t source) const {
  if (source == static_cast<uint8_t>(DepthSource::kSensor)) return options_.stable_confidence;
  if (source == static_cast<uint8_t>(DepthSource::kTransparent))
    return options_.glass.stable_confidence;
  return options_.fill_stable_confidence;
}

bool SurfelFusion::IsStable(const Surfel& s) const {
  return !s.removed() && s.confidence >= StableConfidence(s.source);
}

std::vector<Surfel> SurfelFusion::StableSurfels() const {
  std::vector<Surfel> out;
  for (size_t i = 0; i < map_.size(); ++i)
    if (IsStable(map_[i])) out.push_back(map_[i]);
  return out;
}

SurfelCounts SurfelFusion::Counts() const {
  SurfelCounts c;
  for (size_t i = 0; i < map_.size(); ++i) {
    const Surfel& s = map_[i];
    if (s.removed()) continue;
    const size_t k = std::min<size_t>(s.source, kDepthSources - 1);
    if (IsStable(s)) {
      ++c.stable[k];
      c.stable_area_m2[k] += M_PI * s.radius * s.radius;
    } else {
      ++c.unstable[k];
    }
  }
  return c;
}

size_t SurfelFusion::MemoryBytes() const {
  return map_.MemoryBytes() + index_map_.capacity() * sizeof(uint64_t) +
         front_.capacity() * sizeof(Front) + in_camera_.capacity() * sizeof(Eigen::Vector3f) +
         normal_radius_.capacity() * sizeof(Eigen::Vector4f) +
         results_.capacity() * sizeof(PixelResult) +
         (pixel_of_.capacity() + visible_.capacity() + partner_.capacity()) * sizeof(int32_t) +
         readings_.capacity() * sizeof(EntryReadings) + entry_flags_.capacity() +
         chunks_.capacity() * sizeof(Chunk);
}

void SurfelFusion::MoveWithKeyframes(const std::vector<SE3>& correction) {
  if (correction.empty()) return;
  std::vector<Eigen::Matrix3f> rotation;
  std::vector<Eigen::Vector3f> translation;
  for (const SE3& c : correction) {
    rotation.push_back(c.RotationMatrix().cast<float>());
    translation.push_back(c.translation().cast<float>());
  }
  const int last = static_cast<int>(correction.size()) - 1;
  cv::parallel_for_(cv::Range(0, static_cast<int>(map_.size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      Surfel& s = map_[i];
      if (s.removed() || s.keyframe < 0) continue;
      const int k = std::min(s.keyframe, last);
      s.position = rotation[k] * s.position + translation[k];
      s.normal = rotation[k] * s.normal;
    }
  });
  for (Chunk& c : chunks_) c.dirty = true;
}

void SurfelFusion::AddSurfels(const std::vector<Surfel>& surfels) {
  for (const Surfel& s : surfels) map_.Add(s);
  chunks_.assign((map_.size() + kChunk - 1) / kChunk, Chunk());
}

}  // namespace gf
