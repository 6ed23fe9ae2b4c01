#include "pipeline/run_reader.h"
#include "report/compare_report.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <vector>

#include "acquisition/file_util.h"
#include "acquisition/run_layout.h"
#include "acquisition/trajectory.h"
#include "pipeline/run_sink.h"
#include "report/run_report.h"


namespace gf {
namespace {

using json = nlohmann::ordered_json;

std::string Percent(const json& share) {
  if (!share.is_number()) return "-";
  char buffer[16];
  std::snprintf(buffer, sizeof(buffer), "%.1f%%", 100 * share.get<double>());
  return buffer;
}

// The renderings that exist, with their captions, as seen from the report (prefix + name).
std::vector<std::pair<std::string, std::string>> Renderings(const std::string& out_dir,
                                                            const std::string& prefix,
                                                            const std::string& middle_frame) {
  std::vector<std::pair<std::string, std::string>> images;
  for (const std::string view : {"camera", "above"})
    for (const bool with_fill : {true, false}) {
      const std::string file = RunLayout::Rendering(with_fill, view);
      if (!RunReader(out_dir).Has(file)) continue;
      images.push_back(
          {prefix + file, std::string(with_fill ? "with" : "without") +
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

}  // namespace

void AddComparisonSections(HtmlReport* r, const std::string& out_dir, const std::string& prefix,
                           const ReportFile& file) {
  const RunLayout folder(out_dir), with_fill = folder.Map(true), without_fill = folder.Map(false);
  const json c = json::parse(ReadTextFile(folder.Path(RunLayout::kCompare)));
  const RunReader with_fill_run(with_fill);
  const RunReport run = with_fill_run.Report();
  const std::string input = c["input"];
  const Trajectory estimate = with_fill_run.Poses();
  const std::string truth_file = GroundTruthBeside(input);
  const Trajectory truth = truth_file.empty() ? Trajectory() : ReadTrajectory(truth_file);
  const double ate = c.value("ate_m", 0.0);
  r->Paragraph("Input: " + input +
               ". One tracking run, fused twice: the sensor's depth with the keyframes' stereo "
               "fills (with_fill/) and without them (without_fill/). " +
               RunSummaryText(run, c.contains("ate_m") ? &ate : nullptr));
  r->Heading("The two models");
  const StampedPose& middle = estimate[estimate.size() / 2];
  const int middle_index = run.input.first_frame + static_cast<int>(estimate.size() / 2);
  r->Images(
      Renderings(out_dir, prefix, FrameLabel(IndexedFileName(middle_index, middle.timestamp_text))),
      440);
  AddMapView(r, file,
             {{"with fill", with_fill.dir(), prefix + RunLayout::kWithFill + "/"},
              {"without fill", without_fill.dir(), prefix + RunLayout::kWithoutFill + "/"}});
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
  std::vector<std::pair<std::string, SurfelReport>> maps;
  for (const char* v : {"with_fill", "without_fill"}) {
    const SurfelReport s = c[v]["surfels"].get<SurfelReport>();
    sizes.push_back({v, std::to_string(s.count), std::to_string(s.StableFrom("sensor")),
                     std::to_string(s.StableFrom("stereo_fill")),
                     std::to_string(s.StableFrom("transparent"))});
    maps.push_back({maps.empty() ? "with the fill" : "without", s});
  }
  r->Table({"map", "surfels", "from the sensor", "from the stereo fill", "transparent"}, sizes);
  AddSurfelCountFigure(r, maps);
  r->Heading("Trajectory");
  AddTrajectoryFigure(r, estimate, c.contains("ate_m") ? truth : Trajectory());
  r->Heading("Stereo fill");
  AddFillOverlays(r, with_fill.dir(), prefix + RunLayout::kWithFill + "/");
  r->Heading("Time per stage");
  AddStageTimings(r, run);
  r->Heading("Settings and files");
  AddSettings(r, run);
  r->Links({{prefix + RunLayout::kCompare, RunLayout::kCompare, "the figures above, as numbers"}});
  for (const char* v : {RunLayout::kWithFill, RunLayout::kWithoutFill}) {
    r->Paragraph(std::string(v) + "/:");
    AddFileLinks(r, folder.Path(v), prefix + v + "/");
  }
}

}  // namespace gf
