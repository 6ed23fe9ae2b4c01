#include "eval/map_truth.h"

#include <filesystem>
#include <optional>
#include <sstream>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/depth.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/image_io.h"
#include "acquisition/run_layout.h"
#include "acquisition/trajectory_metrics.h"
#include "surfels/completeness.h"
#include "surfels/ply.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

using json = nlohmann::ordered_json;

// A synthetic capture's ground truth (glassfusion synth): the mesh, its materials' names, the true
// poses and every 5th frame's true depth.
struct Truth {
  TriangleMesh mesh;
  Camera camera;
  Trajectory poses;
  std::vector<TruthView> views;
  std::vector<std::string> materials;
};

std::optional<Truth> LoadTruth(const std::string& input) {
  const fs::path dir(input);
  for (const char* need : {"scene.ply", "groundtruth.txt", "depth.txt", "camera.json"})
    if (!IsRegularFile((dir / need).string())) return std::nullopt;
  if (!IsDirectory((dir / "gt" / "depth").string())) return std::nullopt;
  Truth t;
  t.mesh = ReadTriangleMeshPly((dir / "scene.ply").string());
  const CameraFile camera = LoadCameraFile((dir / "camera.json").string());
  t.camera = camera.camera;
  t.poses = ReadTumTrajectory((dir / "groundtruth.txt").string());
  t.materials = {"diffuse", "glossy", "dark", "textured_glass", "clear_glass"};
  if (IsRegularFile((dir / "synth.json").string())) {
    const json synth = json::parse(ReadTextFile((dir / "synth.json").string()));
    if (synth.contains("materials"))
      t.materials = synth["materials"].get<std::vector<std::string>>();
  }
  std::istringstream lines(ReadTextFile((dir / "depth.txt").string()));
  std::string line;
  for (int k = 0; std::getline(lines, line);) {
    if (line.empty() || line[0] == '#') continue;
    const std::string ts = line.substr(0, line.find(' '));
    if (k++ % 5) continue;
    for (const StampedPose& p : t.poses) {
      if (p.timestamp_text != ts) continue;
      const cv::Mat raw = ReadDepthImage((dir / "gt" / "depth" / (ts + ".png")).string());
      cv::Mat metres;
      raw.convertTo(metres, CV_32F, 1.0 / camera.depth_scale);
      t.views.push_back({metres, p.world_from_camera});
      break;
    }
  }
  return t;
}

json Within(const Completeness& c) {
  if (c.within.size() < 2) return json();
  return {
      {"within_1cm", c.within[0]}, {"within_2cm", c.within[1]}, {"observed_samples", c.observed}};
}

// compare.json's ground-truth part for the map at map_path, whose run followed `est`.
json ScoreMapFile(const std::string& map_path, const Trajectory& est, const Truth& truth_in) {
  const Truth* truth = &truth_in;
  const TrajectoryErrorSummary ate = EvaluateTrajectory(truth->poses, est);
  if (!ate.success) throw InputError(map_path, "its trajectory does not match the ground truth's");
  std::vector<Surfel> map = ReadSurfelPly(map_path);
  const SE3 gt_from_run = AlignPoses(truth->poses, est);
  const Eigen::Matrix3f r = gt_from_run.RotationMatrix().cast<float>();
  const Eigen::Vector3f t = gt_from_run.translation().cast<float>();
  for (Surfel& s : map) s.position = r * s.position + t, s.normal = r * s.normal;
  const MapScore score = ScoreMap(map, truth->mesh, truth->camera, truth->views, {});
  json per_material = json::object();
  for (size_t m = 0; m < truth->materials.size(); ++m)
    if (score.per_material[m].observed > 0)
      per_material[truth->materials[m]] = Within(score.per_material[m]);
  const int stereo = static_cast<int>(DepthSource::kStereo);
  const int glass = static_cast<int>(DepthSource::kTransparent);
  return {
      {"completeness", {{"overall", Within(score.overall)}, {"per_material", per_material}}},
      {"accuracy",
       {{"median_m", score.accuracy_median_m},
        {"p90_m", score.accuracy_p90_m},
        {"fill_surfels", score.source_points[stereo]},
        {"fill_median_m",
         score.source_points[stereo] ? json(score.source_median_m[stereo]) : json()},
        {"fill_p90_m", score.source_points[stereo] ? json(score.source_p90_m[stereo]) : json()},
        {"transparent_surfels", score.source_points[glass]},
        {"transparent_median_m",
         score.source_points[glass] ? json(score.source_median_m[glass]) : json()},
        {"transparent_p90_m",
         score.source_points[glass] ? json(score.source_p90_m[glass]) : json()}}},
      {"ate_m", ate.ate_rmse_m}};
}

}  // namespace

json EvaluateMapAgainstTruth(const std::string& input, const std::string& run_dir) {
  std::optional<Truth> truth = LoadTruth(input);
  if (!truth) return json();
  const RunLayout run(run_dir);
  return ScoreMapFile(run.Path(RunLayout::kMap),
                      ReadTumTrajectory(run.Path(RunLayout::kTrajectory)), *truth);
}

json EvaluateMapFiles(const std::string& map_path, const std::string& mesh_path,
                      const Trajectory& gt, const Trajectory& est) {
  // A synthetic capture's scene.ply: its folder's true depth decides what was observed.
  std::optional<Truth> truth = LoadTruth(fs::path(mesh_path).parent_path().string());
  if (!truth || fs::path(mesh_path).filename() != "scene.ply") {
    truth = Truth();
    truth->mesh = ReadTriangleMeshPly(mesh_path);
    truth->materials = {"diffuse", "glossy", "dark", "textured_glass", "clear_glass"};
  }
  truth->poses = gt;
  return ScoreMapFile(map_path, est, *truth);
}

}  // namespace gf
