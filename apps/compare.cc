#include "apps/compare.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

#include "acquisition/camera.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/image_io.h"
#include "acquisition/run_folder.h"
#include "acquisition/json_text.h"
#include "acquisition/trajectory.h"
#include "acquisition/trajectory_metrics.h"
#include "apps/report_html.h"
#include "apps/run_report.h"
#include "pipeline/run_sink.h"
#include "surfels/completeness.h"
#include "surfels/ply.h"
#include "surfels/render.h"

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

std::string Percent(const json& share) {
  if (!share.is_number()) return "-";
  char buffer[16];
  std::snprintf(buffer, sizeof(buffer), "%.1f%%", 100 * share.get<double>());
  return buffer;
}

// Both maps rendered from the same two viewpoints: the middle frame's, and looking down on the map
// from above and behind that camera. Written as DIR/<map>_<view>.png.
void WriteRenderings(RunFolder* out, const Camera& camera, const Trajectory& trajectory) {
  const std::vector<Surfel> with =
      ReadSurfelPly((fs::path(out->dir()) / "with_fill/map.ply").string());
  const std::vector<Surfel> without =
      ReadSurfelPly((fs::path(out->dir()) / "without_fill/map.ply").string());
  if (trajectory.empty() || with.empty()) return;
  const SE3 middle = trajectory[trajectory.size() / 2].world_from_camera;
  const Eigen::Matrix3d r = middle.RotationMatrix();
  const SE3 above = ViewOfMap(with, camera, r * Eigen::Vector3d(0, 0.8, 0.6), -r.col(1));
  for (const auto& [pose, view] : {std::pair{middle, "camera"}, std::pair{above, "above"}})
    for (const auto& [map, name] :
         {std::pair{&with, "with_fill"}, std::pair{&without, "without_fill"}})
      WriteImage(out->File(std::string(name) + "_" + view + ".png"),
                 RenderSurfels(*map, camera, pose, {}).color);
}

// The renderings that exist, with their captions, as seen from the report (prefix + name).
std::vector<std::pair<std::string, std::string>> Renderings(const std::string& out_dir,
                                                            const std::string& prefix,
                                                            const std::string& middle_frame) {
  std::vector<std::pair<std::string, std::string>> images;
  for (const std::string view : {"camera", "above"})
    for (const std::string map : {"with_fill", "without_fill"}) {
      const std::string file = map + "_" + view + ".png";
      if (!IsRegularFile((fs::path(out_dir) / file).string())) continue;
      images.push_back(
          {prefix + file, std::string(map == "with_fill" ? "with" : "without") +
                              " the fill, seen from " +
                              (view == "camera" ? middle_frame + "'s viewpoint" : "above")});
    }
  return images;
}

std::vector<std::vector<std::string>> CompletenessRows(const json& compare, const char* within) {
  std::vector<std::vector<std::string>> rows;
  const json& w = compare["with_fill"]["completeness"];
  const json& wo = compare["without_fill"]["completeness"];
  rows.push_back(
      {"all observed surfaces", Percent(w["overall"][within]), Percent(wo["overall"][within])});
  for (const auto& [name, c] : w["per_material"].items())
    rows.push_back({name, Percent(c[within]), Percent(wo["per_material"][name][within])});
  return rows;
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

std::string CompareSummary::BriefReport() const {
  char buffer[240];
  std::snprintf(buffer, sizeof(buffer), "%d frames, %ld surfels with the fill, %ld without",
                run.frames, run.surfels, run.surfels_without_fill);
  return buffer;
}

json EvaluateMapAgainstTruth(const std::string& input, const std::string& run_dir) {
  std::optional<Truth> truth = LoadTruth(input);
  if (!truth) return json();
  return ScoreMapFile((fs::path(run_dir) / "map.ply").string(),
                      ReadTumTrajectory((fs::path(run_dir) / "trajectory.txt").string()), *truth);
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

CompareSummary RunCompare(const ReconstructOptions& given) {
  ReconstructOptions options = given;
  options.pipeline.fill = options.pipeline.fusion = true;
  std::string problem;
  if (!options.Check(&problem)) throw InputError(options.out_dir, "bad options: " + problem);
  std::unique_ptr<FrameSource> source = OpenFrameSource(options.input, options.source);
  const fs::path out(options.out_dir);
  // One marker and lock for the whole comparison: with_fill/ and without_fill/ are recorded in it.
  RunFolder::Options folder_options;
  folder_options.earlier = options.force ? RunFolder::kReplace : RunFolder::kRefuse;
  folder_options.inputs = {options.input};
  RunFolder folder(options.out_dir, folder_options);
  FolderRunSink with(&folder, "with_fill");
  FolderRunSink without(&folder, "without_fill");
  CompareSummary summary;
  summary.run = RunPipeline(options, source.get(), &with, &without, "compare");
  json& c = summary.compare;
  c["input"] = options.input;
  c["frames"] = summary.run.frames;
  for (const char* v : {"with_fill", "without_fill"}) {
    c[v]["surfels"] = std::string(v) == "with_fill" ? summary.run.report["surfels"]
                                                    : summary.run.report_without_fill["surfels"];
    const json truth = EvaluateMapAgainstTruth(options.input, (out / v).string());
    if (truth.is_null()) continue;
    c[v]["completeness"] = truth["completeness"];
    c[v]["accuracy"] = truth["accuracy"];
    c["ate_m"] = truth["ate_m"];
  }
  WriteTextFileAtomically(folder.File("compare.json"), JsonText(c) + "\n");
  WriteRenderings(&folder, source->camera(),
                  ReadTumTrajectory((out / "with_fill/trajectory.txt").string()));
  HtmlReport r("GlassFusion: the model with and without the stereo fill");
  AddComparisonSections(&r, options.out_dir, "",
                        [&](const std::string& name) { return folder.File(name); });
  WriteTextFileAtomically(folder.File("report.html"), r.Html());
  return summary;
}

void AddComparisonSections(HtmlReport* r, const std::string& out_dir, const std::string& prefix,
                           const ReportFile& file) {
  const fs::path dir(out_dir);
  const json c = json::parse(ReadTextFile((dir / "compare.json").string()));
  const json run = json::parse(ReadTextFile((dir / "with_fill/report.json").string()));
  const std::string input = c["input"];
  const Trajectory estimate = ReadTumTrajectory((dir / "with_fill/trajectory.txt").string());
  const std::string truth_file = GroundTruthBeside(input);
  const Trajectory truth = truth_file.empty() ? Trajectory() : ReadTrajectory(truth_file);
  const double ate = c.value("ate_m", 0.0);
  r->Paragraph("Input: " + input +
               ". One tracking run, fused twice: the sensor's depth with the keyframes' stereo "
               "fills (with_fill/) and without them (without_fill/). " +
               RunSummaryText(run, c.contains("ate_m") ? &ate : nullptr));
  r->Heading("The two models");
  const StampedPose& middle = estimate[estimate.size() / 2];
  const int middle_index =
      run["input"].value("first_frame", 0) + static_cast<int>(estimate.size() / 2);
  r->Images(
      Renderings(out_dir, prefix, FrameLabel(IndexedFileName(middle_index, middle.timestamp_text))),
      440);
  AddMapView(r, file,
             {{"with fill", (dir / "with_fill").string(), prefix + "with_fill/"},
              {"without fill", (dir / "without_fill").string(), prefix + "without_fill/"}});
  if (c["with_fill"].contains("completeness")) {
    r->Paragraph(
        "Completeness: the share of the true surfaces the camera saw that have a surfel "
        "within 1 cm and within 2 cm (synthetic ground truth).");
    std::vector<std::vector<std::string>> rows = CompletenessRows(c, "within_1cm");
    const std::vector<std::vector<std::string>> cm2 = CompletenessRows(c, "within_2cm");
    for (size_t i = 0; i < rows.size(); ++i)
      rows[i].insert(rows[i].end(), cm2[i].begin() + 1, cm2[i].end());
    r->Table(
        {"surface", "1 cm, with the fill", "1 cm, without", "2 cm, with the fill", "2 cm, without"},
        rows);
    const json& a = c["with_fill"]["accuracy"];
    if (a["fill_median_m"].is_number())
      r->Paragraph(
          "Accuracy of the fill's surfels: median distance to the true surface " +
          std::to_string(static_cast<int>(std::round(1000 * a["fill_median_m"].get<double>()))) +
          " mm, 90% within " +
          std::to_string(static_cast<int>(std::round(1000 * a["fill_p90_m"].get<double>()))) +
          " mm (" + std::to_string(a["fill_surfels"].get<long>()) + " surfels).");
    if (a.contains("transparent_median_m") && a["transparent_median_m"].is_number())
      r->Paragraph("Accuracy of the transparent surfels (clear glass the sensor both read and saw "
                   "through): median distance to the true surface " +
                   std::to_string(static_cast<int>(
                       std::round(1000 * a["transparent_median_m"].get<double>()))) +
                   " mm, 90% within " +
                   std::to_string(static_cast<int>(
                       std::round(1000 * a["transparent_p90_m"].get<double>()))) +
                   " mm (" + std::to_string(a["transparent_surfels"].get<long>()) + " surfels).");
  }
  std::vector<std::vector<std::string>> sizes;
  for (const char* v : {"with_fill", "without_fill"}) {
    const json& s = c[v]["surfels"];
    sizes.push_back({v, std::to_string(s["count"].get<long>()),
                     std::to_string(s["by_source"]["sensor"].get<long>()),
                     std::to_string(s["by_source"]["stereo_fill"].get<long>()),
                     std::to_string(s["by_source"].value("transparent", 0L))});
  }
  r->Table({"map", "surfels", "from the sensor", "from the stereo fill", "transparent"}, sizes);
  AddSurfelCountFigure(
      r, {{"with the fill", c["with_fill"]["surfels"]}, {"without", c["without_fill"]["surfels"]}});
  r->Heading("Trajectory");
  AddTrajectoryFigure(r, estimate, c.contains("ate_m") ? truth : Trajectory());
  r->Heading("Stereo fill");
  AddFillOverlays(r, (dir / "with_fill").string(), prefix + "with_fill/");
  r->Heading("Time per stage");
  AddStageTimings(r, run);
  r->Heading("Settings and files");
  AddSettings(r, run);
  r->Links({{prefix + "compare.json", "compare.json", "the figures above, as numbers"}});
  for (const char* v : {"with_fill", "without_fill"}) {
    r->Paragraph(std::string(v) + "/:");
    AddFileLinks(r, (dir / v).string(), prefix + v + "/");
  }
}

}  // namespace gf
