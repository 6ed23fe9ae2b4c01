#include "pipeline/run_reader.h"
#include "report/run_report.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "acquisition/file_util.h"
#include "acquisition/json_text.h"
#include "acquisition/run_layout.h"
#include "acquisition/trajectory_metrics.h"
#include "pipeline/run_sink.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

using json = nlohmann::ordered_json;

std::string& StoredCommandLine() {
  static std::string line;
  return line;
}

std::string Format(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

}  // namespace

std::vector<std::string> KeyframeFiles(const std::string& run_dir) {
  std::vector<std::string> names;
  const fs::path dir = RunLayout(run_dir).Path(RunLayout::Undistorted("color"));
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return names;
  for (const auto& entry : fs::directory_iterator(dir, ec))
    names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

namespace {

// Two orthonormal directions along which `points` spread most (the plane seen "from above").
std::pair<Eigen::Vector3d, Eigen::Vector3d> MainDirections(
    const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p / points.size();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const auto& p : points) covariance += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  return {solver.eigenvectors().col(2), solver.eigenvectors().col(1)};  // largest first
}

}  // namespace

void SetCommandLine(int argc, char** argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) {
    std::string arg = argv[i];
    const bool plain = !arg.empty() && arg.find_first_not_of(
                                           "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                           "0123456789-_./:=,+@%") == std::string::npos;
    if (!plain) {
      std::string quoted = "'";
      for (char c : arg) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
      arg = quoted + "'";
    }
    line += (i ? " " : "") + arg;
  }
  StoredCommandLine() = line;
}

const std::string& CommandLine() { return StoredCommandLine(); }

std::string FrameLabel(const std::string& file) {
  const std::string stamp = StampOfIndexedName(file);
  if (stamp.empty()) return file;
  const std::string index = file.substr(0, file.find('_'));
  const size_t nonzero = index.find_first_not_of('0');
  return "frame " + (nonzero == std::string::npos ? "0" : index.substr(nonzero)) +
         " (t = " + stamp + " s)";
}

std::string RunSummaryText(const RunReport& report, const double* ate_m) {
  std::string text = std::to_string(report.frames) + " frames in " +
                     Format("%.1f", report.seconds) + " s (" + Format("%.1f", report.fps) +
                     " fps over the whole run), " + std::to_string(report.keyframes) +
                     " keyframes";
  text += ", " + std::to_string(report.tracking.lost_frames) + " frames lost";
  if (report.loops.enabled)
    text += "; " + std::to_string(report.loops.accepted) + " loops accepted";
  if (report.fill)
    text += "; " + Format("%.1f", 100 * report.fill->fill_rate()) +
            "% of the keyframes' hole pixels filled";
  if (report.surfels)
    text += "; " + std::to_string(report.surfels->count) + " surfels (" +
            std::to_string(report.surfels->StableFrom("stereo_fill")) + " from the fill)";
  if (ate_m) text += "; trajectory error (ATE) " + Format("%.2f", 100 * *ate_m) + " cm";
  return text + ".";
}

void AddTrajectoryFigure(HtmlReport* r, const Trajectory& estimate, const Trajectory& truth) {
  if (estimate.size() < 2) return;
  SE3 truth_from_estimate;
  bool aligned = false;
  if (truth.size() >= 3) {
    const TrajectoryErrorSummary ate = EvaluateTrajectory(truth, estimate);
    aligned = ate.success;
    if (aligned) truth_from_estimate = ate.gt_from_estimate;
  }
  std::vector<Eigen::Vector3d> est, gt;
  for (const StampedPose& p : estimate)
    est.push_back(truth_from_estimate * p.world_from_camera.translation());
  if (aligned)  // the ground truth over the run's time only (a run of part of a capture)
    for (const auto& [g, e] : AssociatePoses(truth, estimate, 0.02))
      gt.push_back(truth[g].world_from_camera.translation());
  const auto [a, b] = MainDirections(aligned ? gt : est);
  std::vector<PlotSeries> series;
  if (aligned) series.push_back({"ground truth", "#bbbbbb", {}, 6});  // wide: visible beneath
  series.push_back({"GlassFusion", "#b2182b", {}, 1.5});
  for (const auto& p : gt) series.front().points.push_back({p.dot(a), p.dot(b)});
  for (const auto& p : est) series.back().points.push_back({p.dot(a), p.dot(b)});
  PlotStyle style;
  style.from_zero = false;
  style.equal_aspect = true;
  style.height = 360;
  r->Figure(LinePlotSvg(series, "m, along the main direction of motion", "m, across it", style),
            aligned ? "The camera's path from above (the plane of its two main directions of "
                      "motion), the run's estimate moved onto the ground truth by the best rigid "
                      "alignment, as ATE is measured."
                    : "The camera's path from above (the plane of its two main directions of "
                      "motion); the input has no ground truth.");
}

void AddSurfelCountFigure(HtmlReport* r,
                          const std::vector<std::pair<std::string, SurfelReport>>& runs) {
  static const char* colors[] = {"#1b7837", "#762a83", "#2166ac", "#b2182b"};
  std::vector<PlotSeries> series;
  for (size_t i = 0; i < runs.size(); ++i) {
    if (runs[i].second.count_over_time.empty()) continue;
    PlotSeries s{runs[i].first, colors[i % 4], {}};
    for (const SurfelCountAt& c : runs[i].second.count_over_time)
      s.points.push_back({static_cast<double>(c.frame), static_cast<double>(c.stable)});
    series.push_back(s);
  }
  if (series.empty()) return;
  r->Figure(LinePlotSvg(series, "frame", "stable surfels"),
            "The model's size as the capture goes on (stable surfels: seen often enough to keep).");
}

void AddFillOverlays(HtmlReport* r, const std::string& run_dir, const std::string& prefix,
                     int count) {
  const std::vector<std::string> files = KeyframeFiles(run_dir);
  std::vector<size_t> picks;  // spread evenly, first and last included
  for (int k = 0; k < count && !files.empty(); ++k) {
    const size_t i = count == 1 ? files.size() / 2 : k * (files.size() - 1) / (count - 1);
    if (picks.empty() || picks.back() != i) picks.push_back(i);
  }
  const RunReader run(run_dir);
  std::vector<std::pair<std::string, std::string>> images;
  for (size_t i : picks) {
    const std::string& file = files[i];
    const std::string ts = StampOfIndexedName(file);
    if (ts.empty()) continue;  // no timestamp: keyframes/ names it by index
    const std::string overlay = RunLayout::Keyframe(ts, KeyframeImage::kFillOverlay);
    if (run.Has(overlay))
      images.push_back({prefix + overlay, FrameLabel(file)});
  }
  if (images.empty()) return;
  r->Paragraph(
      "Keyframes' fill: filled pixels green (cyan: carried from earlier keyframes; "
      "brighter = more confident), holes left empty magenta.");
  r->Images(images, 320);
}

void AddStageTimings(HtmlReport* r, const RunReport& report) {
  if (report.stages.steps.empty()) return;
  static const std::vector<std::pair<std::string, std::string>> meaning = {
      {"read", "reading and decoding a frame"},
      {"track", "tracking a frame"},
      {"stereo", "stereo fill of a keyframe (one core)"},
      {"fusion", "fusing a frame into the map"},
      {"fusion_fill", "fusing a keyframe's fill"},
      {"loop_closure", "loop search and pose graph, per keyframe"}};
  std::vector<std::vector<std::string>> rows;
  for (const auto& [name, what] : meaning) {
    const StepTimes* t = report.stages.Find(name);
    if (!t || t->count == 0) continue;
    rows.push_back({name, what, std::to_string(t->count), Format("%.1f", t->median_ms.value_or(0)),
                    Format("%.1f", t->max_ms.value_or(0))});
  }
  r->Table({"stage", "what", "count", "median ms", "max ms"}, rows);
  r->Paragraph("Each stage runs in its own thread; on " +
               std::to_string(report.config.hardware_concurrency) +
               " cores they overlap, so the whole run's rate is not the sum.");
}

void AddSettings(HtmlReport* r, const RunReport& report) {
  if (!CommandLine().empty()) r->Details("the command that made this report", CommandLine());
  r->Details("every setting (report.json \"config\"; --config reads its \"settings\")",
             JsonText(json(report.config)));
}

void AddFileLinks(HtmlReport* r, const std::string& run_dir, const std::string& prefix) {
  static const std::vector<std::pair<std::string, std::string>> files = {
      {RunLayout::kMap,
       "the surfel map (binary PLY: x y z nx ny nz red green blue radius confidence "
       "source)"},
      {RunLayout::kMesh, "a triangle mesh of the map (--mesh)"},
      {RunLayout::kTrajectory, "every frame's world_from_camera (TUM format)"},
      {RunLayout::kReport, "everything on this page, as numbers"},
      {RunLayout::kCamera, "the camera of keyframes/ (the input's, with its lens distortion)"},
      {std::string(RunLayout::kKeyframes) + "/", "per keyframe: hole mask, filled depth (mm), fill overlay, colour"},
      {RunLayout::Undistorted(""), "the keyframes on the pinhole camera: color/, depth/ (mm)"},
      {RunLayout::Undistorted("camera_intrinsic.json"), "their camera, as Open3D reads it"},
      {RunLayout::Undistorted("trajectory.log"), "their poses, as Open3D reads them (Redwood .log)"}};
  std::vector<std::vector<std::string>> links;
  for (const auto& [name, what] : files)
    if (fs::exists(RunLayout(run_dir).Path(name))) links.push_back({prefix + name, name, what});
  r->Links(links);
}

void WriteRunReport(const std::string& run_dir, const std::string& input,
                    const RunReport& report, const ReportFile& file) {
  const Trajectory estimate = RunReader(run_dir).Poses();
  const std::string truth_file = GroundTruthBeside(input);
  const Trajectory truth = truth_file.empty() ? Trajectory() : ReadTrajectory(truth_file);
  const TrajectoryErrorSummary ate = EvaluateTrajectory(truth, estimate);
  HtmlReport r("GlassFusion run: " + fs::path(input).filename().string());
  r.Paragraph("Input: " + input + ". " +
              RunSummaryText(report, ate.success ? &ate.ate_rmse_m : nullptr));
  r.Heading("Trajectory");
  AddTrajectoryFigure(&r, estimate, ate.success ? truth : Trajectory());
  if (report.surfels) {
    r.Heading("The model");
    AddSurfelCountFigure(&r, {{"surfels", *report.surfels}});
    AddMapView(&r, file, {{"the map", run_dir, ""}});
  }
  r.Heading("Stereo fill");
  AddFillOverlays(&r, run_dir, "");
  r.Heading("Time per stage");
  AddStageTimings(&r, report);
  r.Heading("Settings and files");
  AddSettings(&r, report);
  AddFileLinks(&r, run_dir, "");
  WriteTextFileAtomically(RunLayout(run_dir).Path(RunLayout::kPage), r.Html());
}

}  // namespace gf
