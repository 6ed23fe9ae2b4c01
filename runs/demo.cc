#include "runs/demo.h"

#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/image_io.h"
#include "acquisition/input_info.h"
#include "acquisition/json_text.h"
#include "acquisition/progress.h"
#include "acquisition/run_folder.h"
#include "acquisition/run_layout.h"
#include "acquisition/stats.h"
#include "datasets/synth.h"
#include "eval/fill_truth.h"
#include "pipeline/settings.h"
#include "report/compare_report.h"
#include "report/report_html.h"
#include "report/run_report.h"
#include "runs/compare.h"
#include "runs/reconstruct.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

std::string Percent(double f) {
  std::ostringstream s;
  s.precision(1);
  s << std::fixed << 100.0 * f << "%";
  return s.str();
}

// Colour | depth (jet, black = none) | holes over colour (red no return, blue shadow, green out of
// range): what a person should look at to see what the sensor misses.
cv::Mat Overview(const RgbdFrame& frame) {
  cv::Mat depth8;
  frame.depth.convertTo(depth8, CV_8U, 255.0 / 4.0);
  cv::Mat depth_color;
  cv::applyColorMap(depth8, depth_color, cv::COLORMAP_JET);
  depth_color.setTo(cv::Scalar(0, 0, 0), frame.depth == 0);
  cv::Mat holes = frame.color.clone();
  holes.setTo(cv::Scalar(0, 0, 255), frame.hole_mask == static_cast<uint8_t>(HoleCode::kNoReturn));
  holes.setTo(cv::Scalar(255, 0, 0), frame.hole_mask == static_cast<uint8_t>(HoleCode::kShadow));
  holes.setTo(cv::Scalar(0, 200, 0),
              frame.hole_mask == static_cast<uint8_t>(HoleCode::kOutOfRange));
  cv::Mat row;
  cv::hconcat(std::vector<cv::Mat>{frame.color, depth_color, holes}, row);
  cv::resize(row, row, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  return row;
}

}  // namespace

bool DemoOptions::Check(std::string* message) const {
  // A stereo pair needs two frames; the demo renders its capture in memory.
  FieldCheck c(message);
  c.Require(!out_dir.empty(), "--out: the folder to write")
      .In("--frames", frames, 2, 100000, "is more frames than a rendered capture holds");
  return c.ok();
}

namespace {

// The datasets found under the demo's --data folder (default ../shared/datasets), summarised.
nlohmann::ordered_json SummariseDatasets(const DemoOptions& options, std::string* data_dir) {
  *data_dir = options.data_dir;
  if (data_dir->empty() && IsDirectory("../shared/datasets")) *data_dir = "../shared/datasets";
  std::vector<std::string> inputs;
  if (!data_dir->empty() && IsDirectory(*data_dir))
    for (const auto& e : fs::directory_iterator(*data_dir))
      if (e.is_directory() && !DetectInputKind(e.path().string()).empty())
        inputs.push_back(e.path().string());
  std::sort(inputs.begin(), inputs.end());
  nlohmann::ordered_json datasets = nlohmann::ordered_json::array();
  for (const std::string& input : inputs) {
    const std::unique_ptr<Progress> progress = ShowProgress("demo: " + fs::path(input).filename().string(), std::nullopt);
    datasets.push_back(InputInfo(input, {}, [&](int d, int) { progress->Update(d); }));
  }
  return datasets;
}

void AddSceneSections(HtmlReport* r, const DemoOptions& options,
                      const synth::SynthSummary& synth_summary, const SensorHoles& sensor) {
  r->Heading("Built-in glass scene");
  r->Paragraph(
      "A synthetic Kinect v1 capture of a table with frosted and clear glass, shiny metal "
      "and a matte black box (" +
      std::to_string(options.frames) + " frames, " +
      std::to_string(static_cast<int>(1000.0 * synth_summary.seconds_per_frame)) +
      " ms per frame to render), read back through the same path as a real capture. "
      "Frame 0: colour, depth, and the holes over the colour image (red: no return, "
      "blue: projector shadow, green: out of range).");
  r->Images({{"overview.png", "frame 0 (t = 0 s): colour, depth, holes"}}, 960);
  std::vector<std::vector<std::string>> rows;
  for (int m = 0; m < kSynthMaterials; ++m)
    rows.push_back({MaterialName(m), std::to_string(sensor.pixels[m]),
                    Percent(sensor.pixels[m] ? double(sensor.holes[m]) / sensor.pixels[m] : 0)});
  r->Paragraph(
      "The sensor's holes per material (ground-truth labels): what the stereo fill is "
      "for.");
  r->Table({"material", "pixels", "holes"}, rows);
}

void AddFillSections(HtmlReport* r, const FillScore& fill) {
  r->Heading("The stereo fill per material");
  r->Paragraph(
      "Keyframe holes filled by stereo, scored against the true depth of what the colour "
      "camera sees (through clear glass: the background); good = within 3%.");
  std::vector<std::vector<std::string>> rows;
  std::vector<double> errors;
  for (int m = 0; m < kSynthMaterials; ++m) {
    rows.push_back({MaterialName(m), std::to_string(fill.holes[m]),
                    Percent(fill.Rate(fill.filled, m)), Percent(fill.Rate(fill.good, m)),
                    Percent(Median(fill.errors[m]))});
    for (float e : fill.errors[m]) errors.push_back(100.0 * e);
  }
  r->Table({"material", "hole pixels", "filled", "good", "median error"}, rows);
  const int clear_glass = static_cast<int>(synth::Material::kClearGlass);
  r->Paragraph(
      "Filled clear-glass pixels that take the glass's depth instead of the "
      "background's where the map marks no glass (the goal is none): " +
      std::to_string(fill.clear_glass_at_glass_depth) + " of " +
      std::to_string(fill.filled[clear_glass]) + "; where it marks glass (completed from its " +
      "transparent surfels on purpose): " +
      std::to_string(fill.clear_glass_marked_at_glass_depth) + ".");
  r->Figure(HistogramSvg(errors, 10.0, 40, "error of a filled pixel, % of the true depth"),
            "Errors of all " + std::to_string(errors.size()) +
                " filled keyframe pixels (the last bar: 10% and more).");
}

void AddDatasetSection(HtmlReport* r, const std::string& data_dir,
                       const nlohmann::ordered_json& datasets) {
  if (datasets.empty()) return;
  r->Heading("Datasets found under " + data_dir);
  std::vector<std::vector<std::string>> rows;
  for (const auto& j : datasets)
    rows.push_back({fs::path(j["input"].get<std::string>()).filename().string(),
                    j["source"].get<std::string>(), j["frames"].dump(),
                    j["width"].dump() + "x" + j["height"].dump(),
                    j["depth_convention"].get<std::string>(), Percent(j["hole_fraction"]),
                    Percent(j["holes"]["no_return"]), Percent(j["holes"]["shadow"]),
                    Percent(j["holes"]["out_of_range"])});
  r->Table(
      {"input", "kind", "frames", "size", "depth", "holes", "no return", "shadow", "out of range"},
      rows);
}

nlohmann::ordered_json FillJson(const FillScore& fill) {
  nlohmann::ordered_json by_material = nlohmann::ordered_json::object();
  for (int m = 0; m < kSynthMaterials; ++m)
    by_material[MaterialName(m)] = {{"hole_pixels", fill.holes[m]},
                                    {"filled_pixels", fill.filled[m]},
                                    {"fill_rate", fill.Rate(fill.filled, m)},
                                    {"good_rate", fill.Rate(fill.good, m)},
                                    {"median_error", Median(fill.errors[m])}};
  return by_material;
}

}  // namespace

std::string RunDemo(const DemoOptions& options) {
  std::string problem;
  if (!options.Check(&problem)) throw InputError("demo", problem);
  // The reconstruction's settings first: a bad config file stops the demo before it writes.
  ReconstructOptions compare;
  compare.config_file = options.config_file;
  if (!options.config_file.empty()) ApplyConfigFile(options.config_file, &compare.pipeline);
  if (!options.glass) compare.pipeline.fusion_options.fusion.glass.enabled = false;
  // An earlier demo's files go (only those its marker lists); compare/ is a run folder of its own,
  // replaced by its own marker below.
  RunFolder::Options folder_options;
  folder_options.earlier = RunFolder::kReplace;
  if (!options.data_dir.empty()) folder_options.inputs = {options.data_dir};
  RunFolder folder(options.out_dir, folder_options);
  const fs::path out(options.out_dir);
  const std::string scene_dir = (out / "glass-table").string();
  const std::string compare_dir = (out / "compare").string();

  // 1. The built-in glass scene, read back as any capture is, its holes measured per material.
  synth::SynthOptions synth_options;
  synth_options.scene = "glass-table";
  synth_options.frames = options.frames;
  synth_options.seed = 1;
  synth::SynthSummary synth_summary;
  {
    const std::unique_ptr<Progress> progress = ShowProgress("demo: rendering glass-table", options.frames);
    synth_summary = synth::GenerateDataset(synth_options, scene_dir,
                                           [&](int done, int) { progress->Update(done); });
  }
  folder.RecordTree("glass-table");  // moved into place whole (StageFolder, PublishFolder)
  RgbdFrame first;
  const SensorHoles sensor = MeasureSensorHoles(scene_dir, &first);
  WriteImage(folder.File("overview.png"), Overview(first));

  // 2. `compare` on it: tracked once, fused with and without the fill, both maps scored.
  compare.input = scene_dir;
  compare.out_dir = compare_dir;
  compare.force = true;  // compare/'s own marker: only what the earlier demo's comparison wrote
  const CompareSummary c = RunCompare(compare);
  const FillScore fill = ScoreFill(scene_dir, RunLayout(compare_dir).Map(true).dir());
  std::string data_dir;
  const nlohmann::ordered_json datasets = SummariseDatasets(options, &data_dir);

  nlohmann::ordered_json report;
  report["scene"] = {{"name", "glass-table"},
                     {"frames", options.frames},
                     {"folder", scene_dir},
                     {"generation_ms_per_frame", 1000.0 * synth_summary.seconds_per_frame},
                     {"info", InputInfo(scene_dir, {})}};
  report["holes_by_material"] = nlohmann::ordered_json::object();
  for (int m = 0; m < kSynthMaterials; ++m)
    report["holes_by_material"][MaterialName(m)] = {
        {"pixels", sensor.pixels[m]},
        {"hole_fraction", sensor.pixels[m] ? double(sensor.holes[m]) / sensor.pixels[m] : 0.0}};
  report["fill_by_material"] = FillJson(fill);
  report["clear_glass_filled_at_glass_depth"] = fill.clear_glass_at_glass_depth;
  report["clear_glass_marked_at_glass_depth"] = fill.clear_glass_marked_at_glass_depth;
  report["compare"] = c.compare;
  report["config_file"] =
      options.config_file.empty() ? nlohmann::json() : nlohmann::json(options.config_file);
  report["datasets"] = datasets;

  HtmlReport r("GlassFusion demo: a glass scene scanned with and without the stereo fill");
  AddSceneSections(&r, options, synth_summary, sensor);
  AddFillSections(&r, fill);
  r.Heading("The model (glassfusion compare)");
  AddComparisonSections(&r, compare_dir, "compare/",
                        [&](const std::string& name) { return folder.File(name); });
  AddDatasetSection(&r, data_dir, datasets);
  WriteTextFileAtomically(folder.File(RunLayout::kReport), JsonText(report) + "\n");
  WriteTextFileAtomically(folder.File(RunLayout::kPage), r.Html());
  return "glass-table " + synth_summary.BriefReport() + "; " + c.BriefReport() + "; report in " +
         (out / RunLayout::kPage).string();
}

}  // namespace gf
