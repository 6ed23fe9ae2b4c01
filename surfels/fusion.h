// Surfel fusion (Keller et al. 2013; ElasticFusion's data.vert, update.vert and copy_unstable.vert
// on the CPU): every tracked frame's depth, and every keyframe's stereo fill, merged into one map.
//
// Per measurement (a frame, or a keyframe's filled pixels):
//  1. the map's surfels are projected into the camera at the measurement's pose, the nearest per
//     pixel kept (the projected index map);
//  2. each measured pixel (every pixel_step-th each way, the offset alternating between frames;
//     a fill's every fill_pixel_step-th) with a vertex and normal looks for a surfel in the 3x3
//     index-map pixels around it: within max_depth_gap_m along its ray, normals within
//     max_normal_angle_deg (where the surfel faces the camera: normal_test_min_facing); the one
//     nearest the ray wins;
//  3. a match is merged by confidence-weighted averaging of position, normal, colour and radius
//     when the measurement's radius is under max_radius_ratio times the surfel's (a closer, finer
//     view), else only its confidence and time are updated; a pixel without a match starts a new,
//     unstable surfel. A measurement's weight is exp(-r^2 / (2 confidence_sigma^2)), r its distance
//     from the image centre over the half diagonal, times the pixel's own weight (a fill's
//     confidence times fill_weight);
//  4. after a sensor frame: a surfel that the sensor sees through (every measured depth around its
//     pixel farther than it by free_space_margin) loses confidence (unstable surfels and fills are
//     removed); unstable surfels not updated for unstable_frames frames are removed, unconfirmed
//     fills after fill_unstable_frames;
//  5. copies of a surface merge (every merge_copies_every-th frame): two surfels in the same 3x3
//     index-map pixels that lie on one surface (depths within free_space_margin, normals within
//     max_normal_angle_deg whatever their facing), each centre within the other's disc, are
//     merged into the more confident of the two, so passes over the same surface do
//     not stack copies of it;
//  6. the map holds at most max_surfels, fills included (checked after every frame and every
//     fill): beyond it, the least confirmed surfels go (unstable first, then the stable ones seen
//     longest ago).
// Radius: sqrt(2) z / f / |n_z|, at most twice the head-on radius. Fills count fill_weight of a
// sensor measurement, so one keyframe's fill alone never reaches fill_stable_confidence: a fill
// becomes part of the model only when another keyframe's fill agrees with it (within
// free_space_margin in depth: confirm_fills_across_keyframes) or the sensor confirms it.
//
// Per-pixel and per-surfel loops run in parallel through cv::parallel_for_ (the caller's
// cv::setNumThreads decides how many threads); the object itself owns no thread.
//
// Usage:
//   gf::SurfelFusion fusion(camera, {});
//   for (each tracked frame) fusion.FuseFrame(frame, world_from_camera, keyframe_id);
//   for (each filled keyframe) fusion.FuseFill(frame, filled_depth, fill_mask, confidence,
//                                              gf::DepthSource::kStereo, world_from_keyframe, id);
//   gf::WriteSurfelPly("map.ply", fusion.StableSurfels());
#pragma once

#include <array>
#include <cstring>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"
#include "surfels/revolution.h"
#include "surfels/surfel_map.h"

namespace gf {

// FuseFill's mask value for a fill pixel that a view independent of its pair corroborates.
inline constexpr uint8_t kCorroboratedFill = 128;

// The largest map budget (FusionOptions::max_surfels): 16 GiB of surfels, a quarter of a 64 GiB
// workstation's memory, which leaves room for the frames, the fill and the index maps.
inline constexpr long kMaxMapBytes = 16L << 30;
inline constexpr long kMaxMapSurfels = kMaxMapBytes / static_cast<long>(sizeof(Surfel));

// Clear glass in the map: a surface the sensor both reads and sees through. Over the frames that
// see a sensor surfel, the sensor's readings at its pixel and the four next to it (the rays
// through its disc) are counted (Surfel::readings_on, readings_through): on it when their depth
// lands on it (within free_space_margin); through it when all five lie farther by more, and so
// do the readings edge_margin_px away in eight directions (an opaque outline, whose depth edge
// moves a pixel or two between views, lies within that distance on one side). Clear glass lets
// most of the light through (real D435 frames: 44-86% of the readings on clear objects lie
// behind them, tests/glass_sensor_stats.py) and returns the rest from its surface or not at all,
// in patches. So:
//  - a surfel that views after the one that made it read at least min_readings_on times is not
//    removed by one view that sees through it (it loses free_space_penalty, as a stable one);
//  - a sensor surfel read at least min_readings_on times with at least min_through_share of its
//    readings through it is DepthSource::kTransparent (and back when the share falls): the
//    free-space rule leaves it be while views keep reading it (one that no view read for
//    unstable_frames frames goes when the sensor sees through it), and it is part of the model
//    from stable_confidence, the summed weight of the views that read it.
struct GlassOptions {
  bool enabled = true;
  // Readings that landed on the surfel in the views after the one that made it, at least: more
  // than one view's five, so that a glass surface needs two views that read it.
  int min_readings_on = 6;
  // Of the readings that landed on it or passed it, the share that passed it, 0-1: glass is seen
  // through on most of its pixels; an opaque surface only where a misplaced pose or a moving
  // edge puts it, on a few views among many.
  double min_through_share = 1.0 / 3;
  // How far a depth edge of the sensor moves between views, pixels (edge noise and a pixel or two
  // of pose error): a reading counts as through only when the readings this far beside it, in
  // all eight directions (rows, columns, diagonals), pass the surfel too. An opaque outline lies
  // within this distance on one side; a glass surface seen through extends past it.
  int edge_margin_px = 3;
  // A transparent surfel is stable from this confidence (the weight of the sensor's readings that
  // merged into it; a head-on view adds up to 1): clear glass returns a reading on a fraction of
  // its pixels, so it reaches the sensor's stable_confidence many times later than a wall.
  double stable_confidence = 3.0;
  // At the end of a run, objects of transparent surfels that lie on a surface of revolution (a
  // glass, a bottle, a vase) are completed all round (surfels/revolution.h).
  RevolutionOptions revolution;
  bool Check(std::string* message = nullptr) const;
};

struct FusionOptions {
  double min_depth_m = 0.3;  // measurements outside [min_depth_m, max_depth_m] are not fused
  double max_depth_m = 4.0;  // (Kinect noise grows with the square of depth)
  int pixel_step = 2;        // fuse every pixel_step-th pixel each way (1: every pixel)
  // The same for a keyframe's fill. A sensor frame's grid moves on from frame to frame, so that
  // over pixel_step^2 frames every pixel is fused; a fill is fused once, and a coarser grid would
  // leave the rest of its pixels out of the model for good.
  int fill_pixel_step = 1;
  double max_depth_gap_m = 0.05;       // association: surfel within this along the ray, metres
  double max_normal_angle_deg = 30.0;  // ... and normals within this, degrees, for surfels
  // facing the camera: |n_z| of the surfel's normal in the camera at least this. More oblique
  // surfaces have measured normals too noisy to compare (the depth step across the normal's
  // baseline grows with the slant and with the sensor's quantisation), so there the depth gap and
  // the distance to the ray decide alone. ElasticFusion's data.vert: 0.75, within 41 degrees of
  // facing the camera. 0: test every surfel's normal.
  double normal_test_min_facing = 0.75;
  double max_radius_ratio = 1.5;         // merge geometry only when the measured radius is smaller
  double confidence_sigma = 0.6;         // radial weight's sigma, in half image diagonals (at
                                         // most 1000: a flat weight)
  // A sensor surfel is stable from this confidence. Confidences grow by at most about one per
  // frame: those thresholds are at most a day's frames (acquisition/bounds.h).
  double stable_confidence = 10.0;
  int unstable_frames = 20;              // unstable surfels not updated this many frames go
  double fill_weight = 0.5;              // a filled pixel's weight relative to a sensor pixel's
  double fill_stable_confidence = 0.75;  // a fill is confirmed (stable) from this confidence
  // A fill that another keyframe's fill finds on the same surface (depths within
  // free_space_margin of each other, at association or when copies merge) is confirmed at once,
  // whatever the two pixels' weights: two keyframes' pairs agree. Without it a fill is confirmed
  // only when its summed weights reach fill_stable_confidence, which at the stereo's usual
  // per-pixel confidences takes four or more keyframes.
  bool confirm_fills_across_keyframes = true;
  // A fill pixel that FuseFill's mask marks kCorroboratedFill (a view independent of the fill's
  // stereo pair already agrees with it) confirms its surfel at once, as a second keyframe would.
  bool confirm_corroborated_fills = true;
  int fill_unstable_frames = 90;     // unconfirmed fills older than this many frames go
  double free_space_margin = 0.03;   // relative depth by which the sensor must see past a
                                     // surfel to contradict it
  double free_space_penalty = 1.0;   // confidence a stable surfel loses per contradiction
  double max_neighbour_step = 0.05;  // normals only from neighbours within this relative step
  // Copies of a surface (step 5) are merged after every this many sensor frames: the pass costs
  // about a sixth of a frame's fusion, and a copy that waits is only hidden behind the surfel it
  // copies meanwhile (association never reaches it), so the model is the same a few frames later.
  int merge_copies_every = 4;
  // The map's budget, in surfels (48 bytes each: 4 M is 192 MB), sensor surfels and fills alike;
  // beyond it the least confirmed go. At most kMaxMapSurfels (16 GiB).
  long max_surfels = 4'000'000;
  // Normals come from the depth smoothed by a bilateral filter at half size: its diameter in
  // half-size pixels (at most half the largest image side, acquisition/bounds.h) and its depth
  // sigma in metres; then from the smoothed depth this many full-size pixels either side.
  int normal_filter_px = 5;
  double normal_filter_depth_m = 0.05;
  int normal_baseline_px = 2;
  GlassOptions glass;  // clear glass: surfels the sensor both reads and sees through
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

// What one fusion step did.
struct FusionStats {
  int measured = 0;      // pixels considered
  int merged = 0;        // ... that updated a surfel
  int created = 0;       // ... that started one
  int removed = 0;       // surfels removed after the step
  int contradicted = 0;  // surfels the sensor saw through
  int transparent = 0;   // surfels that turned transparent (FusionOptions::glass)
  int redundant = 0;     // surfels merged into another of the same surface
  int over_budget = 0;   // surfels removed to keep the map within max_surfels
  double ms = 0;
  std::string BriefReport() const;
};

// The map seen from a viewpoint (SurfelFusion::RenderView), per pixel.
struct MapView {
  cv::Mat depth;   // CV_32F metres: the nearest stable surfel's disc (RenderDepth); 0 = none
  cv::Mat source;  // CV_8U: its DepthSource (kNone where none)
  // CV_32F: the cosine between its stored normal and the direction back to the camera: 1 seen
  // face-on, 0 edge-on, below 0 from behind (a fill's normal is noisy, yet predicts its error).
  cv::Mat facing;
  // CV_32F: the summed confidence of every stable surfel whose disc the pixel's ray meets no
  // farther than the nearest depth times (1 + support_margin): the measurement weight behind the
  // surface there (a sensor frame adds up to 1, a fill pixel fill_weight times its confidence).
  cv::Mat support;
};

// Surfel counts and area by source (index: DepthSource).
struct SurfelCounts {
  std::array<long, kDepthSources> stable{};    // surfels that reached their source's stable
                                               // confidence
  std::array<long, kDepthSources> unstable{};  // ... that have not
  std::array<double, kDepthSources> stable_area_m2{};  // sum of pi r^2 of the stable ones
  long total_stable() const;
};

class SurfelFusion {
 public:
  // Throws std::logic_error when options.Check() fails.
  SurfelFusion(const Camera& camera, const FusionOptions& options);

  // A tracked frame's sensor depth (frame.depth, metres; colour when it has it), one time step.
  FusionStats FuseFrame(const RgbdFrame& frame, const SE3& world_from_camera, int keyframe);
  // A keyframe's fill: the pixels of `fill_mask` (CV_8U, non-zero; kCorroboratedFill where an
  // independent view corroborates the pixel) of `filled_depth` (CV_32F metres: the sensor's depth
  // plus the fill, for normals across the patch border), each weighted by `confidence` (CV_32F
  // in [0, 1]) and tagged `source`. Not a time step.
  FusionStats FuseFill(const RgbdFrame& frame, const cv::Mat& filled_depth,
                       const cv::Mat& fill_mask, const cv::Mat& confidence, DepthSource source,
                       const SE3& world_from_camera, int keyframe);

  const SurfelMap& map() const { return map_; }
  bool IsStable(const Surfel& s) const;
  // The confidence from which a surfel of `source` (a DepthSource) is stable.
  float StableConfidence(uint8_t source) const;
  // The stable surfels (the model), in map order.
  std::vector<Surfel> StableSurfels() const;
  SurfelCounts Counts() const;
  int frames() const { return frame_; }
  // Bytes the map holds (capacity), for the memory figures.
  size_t MemoryBytes() const;
  // The stable surfels' depth seen from world_from_camera (CV_32F metres, 0 = none): discs of their
  // radius, nearest first (sensor discs along their normals, fill discs facing the camera: a
  // fill's normal is too noisy to orient it); what frame-to-model tracking aligns the next frame
  // to. front_source,
  // when given, gets each pixel's nearest surfel's source (CV_8U DepthSource, kNone where none).
  cv::Mat RenderDepth(const SE3& world_from_camera, cv::Mat* front_source = nullptr);
  // The same rendering with what says how well the map knows each pixel's surface (MapView):
  // the nearest surfel's facing, and the support of the surface within support_margin (a
  // relative depth) of it.
  MapView RenderView(const SE3& world_from_camera, double support_margin);
  // Brings the culling chunks up to date with the map (the renders above do it first). After it,
  // and while the map does not change, RenderDepth and RenderView may run on several threads at
  // once (they then only read the map).
  void SettleChunks();
  // Moves every surfel with the keyframe it belongs to (Surfel::keyframe): by
  // world_correction_of_keyframe[k] (a transform of the world applied on the left), the last entry
  // for keyframes beyond the list; surfels of no keyframe (-1) stay. For a pose-graph correction.
  void MoveWithKeyframes(const std::vector<SE3>& world_correction_of_keyframe);
  // Adds surfels as they are (a map read back, or copies for a benchmark of a large map).
  void AddSurfels(const std::vector<Surfel>& surfels);

 private:
  // One fusion step's input.
  struct Measurement {
    const cv::Mat& depth;   // CV_32F metres
    const cv::Mat& mask;    // CV_8U pixels to fuse (empty: every valid one)
    const cv::Mat& weight;  // CV_32F per-pixel weight (empty: 1)
    double weight_scale;    // times every weight (fill_weight for fills)
    DepthSource source;
    const cv::Mat& color;  // CV_8UC3 BGR (may be empty)
    SE3 world_from_camera;
    int keyframe;
    bool time_step;   // a sensor frame: cleanup follows
    int step;         // every step-th pixel each way ...
    int grid_offset;  // ... from this one
  };
  // One measured pixel after association.
  struct PixelResult {
    int match = -1;  // the entry (index into visible_) of the surfel it merges into, -1 none
    bool valid = false;
    Eigen::Vector3f point, normal;  // camera frame
    float radius = 0, weight = 0;
    uint8_t red = 0, green = 0, blue = 0;
    DepthSource source = DepthSource::kSensor;
    bool corroborated = false;  // a fill pixel marked kCorroboratedFill
  };
  struct StepConstants;
  // One grid row's normals from RowNormals, per grid column: unit, camera frame, facing the
  // camera; has_normal 1 where the neighbours gave one (floats, as the rest: the loop vectorises).
  struct GridRow {
    explicit GridRow(int columns) { Resize(columns); }
    void Resize(int columns) {
      for (std::vector<float>* v : {&nx, &ny, &nz, &has_normal}) v->resize(columns);
    }
    std::vector<float> nx, ny, nz, has_normal;
  };
  FusionStats Fuse(const Measurement& m);
  // The measured pixels of image row y (every m.step-th from grid_offset): each one's vertex,
  // normal, radius, weight, colour and the surfel it associates with (valid false: not measurable).
  // grid: scratch for the row's normals.
  void MeasureRow(const Measurement& m, const StepConstants& k, int y, PixelResult* row,
                  GridRow* grid) const;
  // The normals of grid columns [first, end) of image row y, from the smoothed half-size depth.
  void RowNormals(const cv::Mat& smooth, int step, int grid_offset, int y, int first, int end,
                  GridRow* grid) const;
  // The entry (index into visible_) of the surfel the measured pixel at (x, y) associates with,
  // -1 none; `ray` is the pixel's (x/z, y/z).
  int NearestAlongRay(const StepConstants& k, int x, int y, const cv::Vec2f& ray,
                      const PixelResult& res) const;
  void Integrate(const Measurement& m, const std::vector<PixelResult>& results, FusionStats* stats);
  // The confidence of fill surfel s after another fill, of `other_keyframe`, with depth
  // `other_z` (s's own at this step: `z`, both in one camera), adds `confidence` to s's: at least
  // fill_stable_confidence when the two are of different keyframes and agree in depth.
  float FillConfidence(const Surfel& s, float confidence, int other_keyframe, float z,
                       float other_z) const;
  // `confidence`, raised to fill_stable_confidence for a corroborated fill pixel
  // (confirm_corroborated_fills).
  float WithCorroboration(float confidence, bool corroborated) const;
  // The entries of this step (the surfels of the chunks in view) and the index map: culling, then
  // ProjectEntries (each entry's position in the camera and its pixel), then NearestPerPixel (the
  // nearest entry per pixel and its front data).
  void ProjectMap(const SE3& camera_from_world);
  void ProjectEntries(const SE3& camera_from_world);
  void NearestPerPixel();
  void CleanUp(const Measurement& m, FusionStats* stats);
  void RemoveSeenThrough(const Measurement& m, FusionStats* stats);
  // RemoveSeenThrough's second half, in entry order: the readings_ it gathered applied to the
  // surfels (transparent or not, free space's penalty or removal).
  void ApplyReadings(FusionStats* stats);
  void MergeRedundant(FusionStats* stats);
  // Sets partner_[e] to the entry that entry e is a copy of (-1: none), for MergeRedundant.
  void FindCopies();
  void KeepWithinBudget(FusionStats* stats);
  // Drops the removed surfels from the map's storage (SurfelMap::Compact) and renews the chunks
  // that moved.
  void CompactMap();
  // A surfel changed: its chunk is no longer settled.
  void Touch(size_t surfel) { chunks_[surfel / kChunk].settled = false; }
  // ... and its position or radius may have: the chunk's bounds grow to hold it.
  void TouchGeometry(size_t surfel) {
    Chunk& chunk = chunks_[surfel / kChunk];
    chunk.settled = false;
    if (!chunk.dirty) chunk.Include(map_[surfel]);  // (dirty: recomputed before its next use)
  }
  // Recomputes a dirty chunk's bounds.
  void RefreshChunk(size_t chunk);
  bool ChunkVisible(size_t chunk, const SE3& camera_from_world) const;
  // Calls visit(surfel, its normal in the camera, the pixel's ray (x/z, y/z, 1), x, y, depth) for
  // every pixel a stable surfel's disc covers (RenderDepth's discs).
  template <typename Visit>
  void ForEachSplatPixel(const SE3& world_from_camera, Visit visit);

  // Surfels are culled by chunks of kChunk consecutive ones (created together, so close together)
  // with a bounding sphere: around the box that holds their positions, plus the largest radius.
  // The box grows as surfels are added or move (TouchGeometry); it is recomputed from the surfels
  // only when they all moved (a pose-graph correction) or the chunk is new. Removals leave it as
  // it was: a larger sphere only culls less, and compaction starts the chunks it changed anew.
  static constexpr size_t kChunk = 1024;
  static_assert(SurfelMap::kBlock % kChunk == 0, "a chunk's surfels lie in one block of the map");
  static constexpr uint64_t kEmpty = ~uint64_t{0};  // an index-map pixel no surfel projects to
  // Loops that read memory at random (the index map in entry order, surfels in pixel order) fetch
  // the item this many iterations ahead, so that its cache miss overlaps the work in between.
  static constexpr int kPrefetch = 16;
  struct Chunk {
    // The box of the positions (lo > hi: none) and the largest radius, world frame.
    Eigen::Vector3f lo = Eigen::Vector3f::Zero(), hi = Eigen::Vector3f::Zero();
    float largest = 0;
    bool dirty = true;     // the bounds must be recomputed from the surfels
    bool settled = false;  // no unstable surfel at the last full sweep, and untouched since
    // Grows the bounds to hold s.
    void Include(const Surfel& s) {
      lo = lo.cwiseMin(s.position);
      hi = hi.cwiseMax(s.position);
      largest = std::max(largest, s.radius);
    }
  };
  std::vector<Chunk> chunks_;
  std::vector<uint8_t> in_view_;                   // per chunk, in view this step
  std::vector<size_t> entry_offset_;               // per chunk in view, its first entry
  float view_x_[2] = {0, 0}, view_y_[2] = {0, 0};  // the image's extent in x/z and y/z

  Camera camera_;
  FusionOptions options_;
  cv::Mat rays_;           // CV_32FC2: each pixel's ray (x/z, y/z), lens distortion removed
  cv::Mat radial_weight_;  // CV_32F: each pixel's weight by its distance from the image centre
  // CV_32F, half size: the ray (x/z, y/z) of the pixel whose depth each cell of the half-size
  // depth holds (the same nearest-pixel resize).
  cv::Mat half_ray_x_, half_ray_y_;
  SurfelMap map_;
  int frame_ = 0;  // time steps (sensor frames) so far
  int fills_ = 0;  // fills fused so far (their pixel grid offset alternates too)
  // Per fusion step: the surfels of the chunks in view (entries: visible_ holds their map index),
  // with their position in the camera and their pixel (y * width + x, -1 when not in
  // the image), and the projected index map (nearest entry per pixel, packed depth and entry).
  std::vector<uint32_t> visible_;
  // The rotation of this step's camera_from_world.
  Eigen::Matrix3f camera_rotation_ = Eigen::Matrix3f::Identity();
  std::vector<Eigen::Vector3f> in_camera_;
  // Per entry, its surfel's world normal and radius (set where the surfel is not removed), so that
  // the per-pixel searches read the entries of this step, not the whole map.
  std::vector<Eigen::Vector4f> normal_radius_;
  std::vector<int32_t> pixel_of_;
  // Per entry, what the cleanup after a step needs to know without reading the surfel: set when a
  // pixel merged into it this step (kUpdated), and when it may go stale at this step's cleanup
  // (kMayGoStale: unstable at projection and not updated for its source's window, so the cleanup
  // re-checks it unless a pixel updated it; or it lost confidence to free space since, so it may
  // be unstable now).
  static constexpr uint8_t kUpdated = 1, kMayGoStale = 2;
  std::vector<uint8_t> entry_flags_;
  std::vector<uint64_t> index_map_;
  // The depth and entry an index-map cell packs (the depth's bits above the entry's, so that the
  // smaller word is the nearer entry).
  static float CellDepth(uint64_t cell) {
    const uint32_t bits = static_cast<uint32_t>(cell >> 32);
    float z;
    std::memcpy(&z, &bits, sizeof(z));
    return z;
  }
  static uint32_t CellEntry(uint64_t cell) { return static_cast<uint32_t>(cell); }
  // Per pixel, the rest of its front entry's data (valid where index_map_ is not kEmpty, which
  // holds its depth and entry), copied out of the entry arrays after projection: the per-pixel
  // searches then read memory in pixel order. The per-pixel searches stream it (24 bytes a pixel,
  // 7 MB at 640x480), so it holds nothing the index map has.
  struct Front {
    float x, y;              // position in the camera (its z: the cell's depth)
    Eigen::Vector3f normal;  // in the camera (compared with measured normals as it is)
    float radius;
  };
  std::vector<Front> front_;
  std::vector<PixelResult> results_;  // per measured pixel of the step
  // Per step, kept between steps (a step allocates only while the map grows, and in the rare
  // budget pass): the depth at half size and bilateral-filtered (for normals); per entry, the
  // sensor's readings around it (RemoveSeenThrough) and the copy it merges into.
  cv::Mat half_depth_, smooth_half_;
  // The sensor pixels in the 3x3 around an entry's pixel: measured, seeing through it; of the
  // pixel and its four neighbours, those landing on it and seeing through it (the glass counts);
  // whether the sensor saw through it (free space: not updated, every measured one through it,
  // at least five measured); and whether its source turned transparent, or back.
  struct EntryReadings {
    uint8_t measured = 0, through = 0, counted = 0, counted_on = 0, counted_through = 0;
    bool seen_through = false, turned = false;
  };
  std::vector<EntryReadings> readings_;
  std::vector<int32_t> partner_;
};

}  // namespace gf
