#include "fill/colmap_workspace.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "acquisition/bounds.h"
#include "acquisition/camera.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/image_io.h"
#include "acquisition/json_text.h"
#include "acquisition/run_folder.h"
#include "acquisition/run_layout.h"
#include "acquisition/stats.h"
#include "acquisition/trajectory.h"
#include "fill/colmap_io.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

// Keyframe timestamps of a run (from keyframes/<ts>.color.png), in time order.
std::vector<std::string> RunKeyframes(const std::string& run_dir) {
  const std::string dir = RunLayout(run_dir).Path(RunLayout::kKeyframes);
  if (!IsDirectory(dir))
    throw InputError(dir, "no keyframes folder (run `glassfusion reconstruct` first)");
  std::vector<std::string> stamps;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name =
        RunLayout::KeyframeOf(entry.path().filename().string(), KeyframeImage::kColor);
    if (!name.empty()) stamps.push_back(name);
  }
  if (stamps.empty()) throw InputError(dir, "no <ts>.color.png keyframe images");
  std::sort(stamps.begin(), stamps.end(),
            [](const std::string& a, const std::string& b) { return std::stod(a) < std::stod(b); });
  return stamps;
}

}  // namespace

std::string ColmapExportSummary::BriefReport() const {
  return std::to_string(images) + " keyframe images with tracked poses";
}

ColmapExportSummary RunColmapExport(const std::string& run_dir, const std::string& workspace) {
  const RunLayout run(run_dir);
  const CameraFile camera = LoadCameraFile(run.Path(RunLayout::kCamera));
  const Trajectory trajectory = ReadTumTrajectory(run.Path(RunLayout::kTrajectory));
  std::map<std::string, SE3> poses;
  for (const StampedPose& p : trajectory) poses[p.timestamp_text] = p.world_from_camera;
  const std::vector<std::string> stamps = RunKeyframes(run_dir);

  const std::string staging = StageFolder(workspace);
  fs::create_directories(fs::path(staging) / "images");
  std::vector<ColmapImage> images;
  for (const std::string& ts : stamps) {
    const auto pose = poses.find(ts);
    if (pose == poses.end())
      throw InputError(run.Path(RunLayout::kTrajectory),
                       "no pose for keyframe " + ts);
    ColmapImage image;
    image.id = static_cast<int>(images.size()) + 1;
    image.name = IndexedFileName(image.id, ts);
    image.world_from_camera = pose->second;
    fs::copy_file(run.Path(ts, KeyframeImage::kColor),
                  fs::path(staging) / "images" / image.name);
    images.push_back(image);
  }
  WriteColmapTextModel((fs::path(staging) / "sparse" / "0").string(), camera.camera, images);
  PublishFolder(staging, workspace);
  ColmapExportSummary summary;
  summary.images = static_cast<int>(images.size());
  return summary;
}

bool ColmapImportOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.Above("max_sensor_error", max_sensor_error, 0, kMaxRelativeDepth, kBeyondAnyDepthRange)
      .In("min_sensor_samples", min_sensor_samples, 1, kMaxImagePixels, kMoreThanAnImagesPixels)
      .Above("min_depth_m", min_depth_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .Above("max_depth_m", max_depth_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .Require(max_depth_m > min_depth_m, "max_depth_m must be more than min_depth_m");
  return c.ok();
}

std::string ColmapImportSummary::BriefReport() const {
  char buffer[200];
  std::snprintf(buffer, sizeof(buffer),
                "%d refined keyframe poses; %d depth maps, %d agreeing with the sensor, %ld hole "
                "pixels filled from them",
                poses, depth_maps, depth_maps_used, filled_pixels);
  return buffer;
}

namespace {

// The refined poses of the workspace's text model into the run's trajectory_colmap.txt. Returns
// the model's folder ("" when there is none and none was asked for); *poses: how many.
std::string ImportRefinedPoses(const std::string& workspace, const ColmapImportOptions& options,
                               RunFolder* run, int* poses) {
  const std::string model_dir =
      options.model_dir.empty() ? (fs::path(workspace) / "refined").string() : options.model_dir;
  const std::string images_txt = (fs::path(model_dir) / "images.txt").string();
  if (!options.model_dir.empty() && !IsRegularFile(images_txt))
    throw InputError(images_txt,
                     "no text model (convert with colmap model_converter "
                     "--output_type TXT)");
  if (!IsRegularFile(images_txt)) return "";
  std::vector<ColmapImage> images = ReadColmapImages(images_txt);
  Trajectory refined;
  for (const ColmapImage& image : images) {
    const std::string ts = StampOfIndexedName(image.name);
    if (ts.empty())
      throw InputError(images_txt, "image " + image.name + " is not from colmap-export");
    refined.push_back({std::stod(ts), ts, image.world_from_camera});
  }
  std::sort(refined.begin(), refined.end(),
            [](const StampedPose& a, const StampedPose& b) { return a.timestamp < b.timestamp; });
  WriteTumTrajectory(run->File("trajectory_colmap.txt"), refined);
  *poses = static_cast<int>(refined.size());
  return model_dir;
}

// The dense depth maps of a workspace: where they are and on which camera's grid.
struct DenseMaps {
  fs::path dense;                     // holds stereo/depth_maps/ ("" when none)
  std::optional<Camera> grid_camera;  // the undistorted camera of the maps (none: the run's)
};

DenseMaps FindDenseMaps(const std::string& workspace) {
  DenseMaps d;
  for (const fs::path& dir : {fs::path(workspace), fs::path(workspace) / "dense"})
    if (IsDirectory((dir / "stereo" / "depth_maps").string())) {
      d.dense = dir;
      break;
    }
  if (!d.dense.empty() && IsRegularFile((d.dense / "sparse" / "cameras.txt").string())) {
    const auto cameras = ReadColmapCameras((d.dense / "sparse" / "cameras.txt").string());
    if (!cameras.empty()) d.grid_camera = cameras.begin()->second;
  }
  return d;
}

// Keyframe `ts`'s depth map merged into its depth_filled.png: its holes take the map's depth
// where the map agrees with the sensor's pixels (median relative error within
// options.max_sensor_error over options.min_sensor_samples or more). Returns the map's entry
// of colmap_import.json.
nlohmann::ordered_json MergeDepthMap(const fs::path& map_path, const std::string& ts,
                                     const Camera& camera, const DenseMaps& dense,
                                     const ColmapImportOptions& options, RunFolder* run,
                                     ColmapImportSummary* summary) {
  const cv::Mat map = ReadColmapDepthMap(map_path.string());
  const Camera grid = dense.grid_camera ? *dense.grid_camera : camera;
  if (map.cols != grid.width || map.rows != grid.height)
    throw InputError(map_path.string(), "size differs from the workspace camera");
  const RunLayout layout(run->dir());
  const std::string mask_path = layout.Path(ts, KeyframeImage::kHoleMask);
  cv::Mat filled = ReadDepthImage(layout.Path(ts, KeyframeImage::kDepthFilled));
  const cv::Mat holes = cv::imread(mask_path, cv::IMREAD_UNCHANGED);
  if (holes.type() != CV_8UC1 || holes.size() != filled.size())
    throw InputError(mask_path, "missing, or not an 8-bit mask of the depth's size");
  // Where keyframe pixel (x, y) lands in the depth map's grid.
  auto lookup = [&](int x, int y) -> float {
    int u = x, v = y;
    if (dense.grid_camera) {
      const Eigen::Vector2d n = camera.UndistortPixel({x, y});
      u = static_cast<int>(std::lround(grid.fx * n.x() + grid.cx));
      v = static_cast<int>(std::lround(grid.fy * n.y() + grid.cy));
      if (u < 0 || v < 0 || u >= grid.width || v >= grid.height) return 0.f;
    }
    const float z = map.at<float>(v, u);
    return z >= options.min_depth_m && z <= options.max_depth_m ? z : 0.f;
  };
  std::vector<float> errors;
  for (int y = 0; y < filled.rows; ++y)
    for (int x = 0; x < filled.cols; ++x) {
      if (holes.at<uint8_t>(y, x) != 0 || filled.at<uint16_t>(y, x) == 0) continue;
      const float z = lookup(x, y), sensor = filled.at<uint16_t>(y, x) / 1000.f;
      if (z > 0) errors.push_back(std::abs(z - sensor) / sensor);
    }
  const double error = Median(errors, 1.f);
  const bool agrees = static_cast<int>(errors.size()) >= options.min_sensor_samples &&
                      error <= options.max_sensor_error;
  long added = 0;
  if (agrees) {
    for (int y = 0; y < filled.rows; ++y)
      for (int x = 0; x < filled.cols; ++x) {
        if (holes.at<uint8_t>(y, x) == 0 || filled.at<uint16_t>(y, x) != 0) continue;
        const float z = lookup(x, y);
        if (z <= 0) continue;
        filled.at<uint16_t>(y, x) = static_cast<uint16_t>(std::min(65535.f, z * 1000.f + 0.5f));
        ++added;
      }
    WriteImage(run->File(RunLayout::Keyframe(ts, KeyframeImage::kDepthFilled)), filled);
    ++summary->depth_maps_used;
    summary->filled_pixels += added;
  }
  spdlog::debug("colmap depth map {}: sensor error {:.2f}% over {} px, {} filled",
                map_path.filename().string(), 100 * error, errors.size(), added);
  return {{"timestamp", ts},
          {"depth_map", map_path.string()},
          {"sensor_samples", errors.size()},
          {"sensor_error_median",
           errors.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(error)},
          {"used", agrees},
          {"filled_pixels", added}};
}

}  // namespace

ColmapImportSummary RunColmapImport(const std::string& workspace, const std::string& run_dir,
                                    const ColmapImportOptions& options) {
  std::string problem;
  if (!options.Check(&problem)) throw InputError(workspace, problem);
  if (!IsDirectory(workspace)) throw InputError(workspace, "no such COLMAP workspace");
  const CameraFile run_camera = LoadCameraFile(RunLayout(run_dir).Path(RunLayout::kCamera));
  // Adds to the run: locked against a run writing it, what it adds listed in its marker.
  RunFolder::Options folder_options;
  folder_options.earlier = RunFolder::kKeep;  // the workspace may well lie inside the run
  RunFolder run(run_dir, folder_options);
  ColmapImportSummary summary;
  nlohmann::ordered_json report;
  const std::string model_dir = ImportRefinedPoses(workspace, options, &run, &summary.poses);
  if (!model_dir.empty()) report["model"] = model_dir;

  // Depth maps as a fill source, in the order of the workspace's image names.
  const DenseMaps dense = FindDenseMaps(workspace);
  nlohmann::ordered_json maps = nlohmann::ordered_json::array();
  const fs::path images_dir = fs::path(workspace) / "images";
  if (!dense.dense.empty() && IsDirectory(images_dir.string())) {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(images_dir))
      names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    for (const std::string& name : names) {
      fs::path map_path;
      for (const char* kind : {".geometric.bin", ".photometric.bin"}) {
        const fs::path p = dense.dense / "stereo" / "depth_maps" / (name + kind);
        if (IsRegularFile(p.string())) {
          map_path = p;
          break;
        }
      }
      const std::string ts = StampOfIndexedName(name);
      if (map_path.empty() || ts.empty()) continue;
      ++summary.depth_maps;
      maps.push_back(
          MergeDepthMap(map_path, ts, run_camera.camera, dense, options, &run, &summary));
    }
  }
  report["poses"] = summary.poses;
  report["depth_maps"] = maps;
  report["filled_pixels"] = summary.filled_pixels;
  WriteTextFileAtomically(run.File("colmap_import.json"), JsonText(report) + "\n");
  return summary;
}

}  // namespace gf
