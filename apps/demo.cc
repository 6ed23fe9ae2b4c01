#include "apps/demo.h"

#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/image_io.h"
#include "acquisition/stats.h"
#include "acquisition/trajectory.h"
#include "acquisition/trajectory_metrics.h"
#include "apps/info.h"
#include "apps/progress.h"
#include "apps/reconstruct.h"
#include "apps/report_html.h"
#include "datasets/synth.h"
#include "pipeline/settings.h"

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
  if (out_dir.empty() || frames < 2) {
    if (message) *message = "need an output folder and at least 2 frames";
    return false;
  }
  return true;
}

void RunDemo(const DemoOptions& options) {
  std::string problem;
  if (!options.Check(&problem)) throw InputError("demo", problem);
  // The reconstruction's settings first: a bad config file stops the demo before it writes.
  ReconstructOptions reconstruct;
  reconstruct.config_file = options.config_file;
  if (!options.config_file.empty()) ApplyConfigFile(options.config_file, &reconstruct.pipeline);
  std::error_code ec;
  fs::create_directories(options.out_dir, ec);
  if (ec) throw InputError(options.out_dir, "cannot create output folder: " + ec.message());
  const std::string scene_dir = (fs::path(options.out_dir) / "glass-table").string();
  // A previous demo's scene is replaced; anything else in the way is not ours to delete.
  if (fs::exists(scene_dir)) {
    if (!IsRegularFile((fs::path(scene_dir) / "synth.json").string()))
      throw InputError(scene_dir, "exists and is not a GlassFusion synthetic dataset");
    fs::remove_all(scene_dir);
  }

  // 1. The built-in glass scene.
  synth::SynthOptions synth_options;
  synth_options.scene = "glass-table";
  synth_options.frames = options.frames;
  synth_options.seed = 1;
  synth::SynthSummary synth_summary;
  {
    TerminalProgress progress("demo: rendering glass-table", options.frames);
    synth_summary = synth::GenerateDataset(synth_options, scene_dir,
                                           [&](int done, int) { progress.Update(done); });
  }

  // 2. Read it back as any capture is read, and measure holes per material against ground truth.
  FrameSourceOptions source_options;
  auto source = OpenFrameSource(scene_dir, source_options);
  std::vector<size_t> material_holes(5, 0), material_pixels(5, 0);
  RgbdFrame frame, first;
  while (source->Next(&frame)) {
    const cv::Mat label =
        cv::imread((fs::path(scene_dir) / "gt/label" / (frame.timestamp_text + ".png")).string(),
                   cv::IMREAD_UNCHANGED);
    if (label.empty())
      throw InputError(scene_dir, "ground-truth label of " + frame.timestamp_text + " missing");
    for (int v = 0; v < label.rows; ++v)
      for (int u = 0; u < label.cols; ++u) {
        const int m = label.at<uint8_t>(v, u);
        if (m >= 5) continue;
        ++material_pixels[m];
        material_holes[m] += frame.hole_mask.at<uint8_t>(v, u) != 0;
      }
    if (frame.index == 0) first = frame;
  }
  WriteImage((fs::path(options.out_dir) / "overview.png").string(), Overview(first));
  const auto scene_info = InputInfo(scene_dir, source_options);

  // 3. Reconstruct it (tracking + stereo fill) and score the fill per material against ground
  // truth: a filled pixel should hold the depth of what the colour camera sees there (through
  // clear glass: the background).
  const std::string run_dir = (fs::path(options.out_dir) / "run").string();
  if (fs::exists(run_dir)) {
    if (!IsRegularFile((fs::path(run_dir) / "report.json").string()))
      throw InputError(run_dir, "exists and is not a GlassFusion run folder");
    fs::remove_all(run_dir);
  }
  reconstruct.input = scene_dir;
  reconstruct.out_dir = run_dir;
  const ReconstructionSummary run = RunReconstruct(reconstruct);
  const TrajectoryErrorSummary ate =
      EvaluateTrajectory(ReadTumTrajectory((fs::path(scene_dir) / "groundtruth.txt").string()),
                         ReadTumTrajectory((fs::path(run_dir) / "trajectory.txt").string()));
  const double truth_scale =
      LoadCameraFile((fs::path(scene_dir) / "camera.json").string()).depth_scale;
  std::vector<size_t> fill_holes(5, 0), fill_filled(5, 0), fill_good(5, 0);
  // Filled clear-glass pixels that take the glass's own depth instead of the background's (what
  // the colour camera sees through it): the goal is none.
  const int clear_glass = static_cast<int>(synth::Material::kClearGlass);
  size_t clear_glass_at_glass_depth = 0;
  std::vector<std::vector<float>> fill_errors(5);
  std::string overlay_ts;
  int best_filled = -1;
  for (const auto& entry : fs::directory_iterator(fs::path(run_dir) / "keyframes")) {
    const std::string name = entry.path().filename().string();
    const std::string suffix = ".depth_filled.png";
    if (name.size() <= suffix.size() ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix))
      continue;
    const std::string ts = name.substr(0, name.size() - suffix.size());
    const cv::Mat filled = ReadDepthImage(entry.path().string());
    const cv::Mat holes = cv::imread(
        (fs::path(run_dir) / "keyframes" / (ts + ".hole_mask.png")).string(), cv::IMREAD_UNCHANGED);
    const cv::Mat label = cv::imread((fs::path(scene_dir) / "gt/label" / (ts + ".png")).string(),
                                     cv::IMREAD_UNCHANGED);
    const cv::Mat truth =
        ReadDepthImage((fs::path(scene_dir) / "gt/visible_depth" / (ts + ".png")).string());
    const cv::Mat first_surface =
        ReadDepthImage((fs::path(scene_dir) / "gt/depth" / (ts + ".png")).string());
    if (holes.empty() || label.empty())
      throw InputError(run_dir, "keyframe " + ts + ": mask or label missing");
    int filled_here = 0;
    for (int v = 0; v < label.rows; ++v)
      for (int u = 0; u < label.cols; ++u) {
        const int m = label.at<uint8_t>(v, u);
        if (m >= 5 || holes.at<uint8_t>(v, u) == 0) continue;
        ++fill_holes[m];
        const double z = filled.at<uint16_t>(v, u) / 1000.0,
                     t = truth.at<uint16_t>(v, u) / truth_scale;
        if (z <= 0 || t <= 0) continue;
        ++fill_filled[m];
        ++filled_here;
        const double e = std::abs(z - t) / t;
        fill_errors[m].push_back(static_cast<float>(e));
        fill_good[m] += e <= 0.03;
        clear_glass_at_glass_depth +=
            m == clear_glass &&
            synth::AtClearGlassDepth(z, first_surface.at<uint16_t>(v, u) / truth_scale, t);
      }
    if (filled_here > best_filled) {
      best_filled = filled_here;
      overlay_ts = ts;
    }
  }
  if (!overlay_ts.empty())
    fs::copy_file(fs::path(run_dir) / "keyframes" / (overlay_ts + ".fill_overlay.png"),
                  fs::path(options.out_dir) / "fill_overlay.png",
                  fs::copy_options::overwrite_existing);

  // 4. Real datasets, when they are on this machine.
  std::string data_dir = options.data_dir;
  if (data_dir.empty() && IsDirectory("../shared/datasets")) data_dir = "../shared/datasets";
  std::vector<std::string> inputs;
  if (!data_dir.empty() && IsDirectory(data_dir))
    for (const auto& e : fs::directory_iterator(data_dir))
      if (e.is_directory() && !DetectInputKind(e.path().string()).empty())
        inputs.push_back(e.path().string());
  std::sort(inputs.begin(), inputs.end());

  nlohmann::ordered_json report;
  report["scene"] = {{"name", "glass-table"},
                     {"frames", options.frames},
                     {"folder", scene_dir},
                     {"generation_ms_per_frame", 1000.0 * synth_summary.seconds_per_frame},
                     {"info", scene_info}};
  nlohmann::ordered_json per_material = nlohmann::ordered_json::object();
  for (int m = 0; m < 5; ++m)
    per_material[synth::MaterialName(static_cast<synth::Material>(m))] = {
        {"pixels", material_pixels[m]},
        {"hole_fraction",
         material_pixels[m] ? static_cast<double>(material_holes[m]) / material_pixels[m] : 0.0}};
  report["holes_by_material"] = per_material;
  report["tracking"] = {{"frames", run.frames},
                        {"fps", run.fps},
                        {"keyframes", run.keyframes},
                        {"ate_rmse_m", ate.success ? nlohmann::ordered_json(ate.ate_rmse_m)
                                                   : nlohmann::ordered_json()}};
  nlohmann::ordered_json fill_by_material = nlohmann::ordered_json::object();
  for (int m = 0; m < 5; ++m)
    fill_by_material[synth::MaterialName(static_cast<synth::Material>(m))] = {
        {"hole_pixels", fill_holes[m]},
        {"filled_pixels", fill_filled[m]},
        {"fill_rate", fill_holes[m] ? double(fill_filled[m]) / fill_holes[m] : 0.0},
        {"good_rate", fill_holes[m] ? double(fill_good[m]) / fill_holes[m] : 0.0},
        {"median_error", Median(fill_errors[m])}};
  report["fill_by_material"] = fill_by_material;
  report["clear_glass_filled_at_glass_depth"] = clear_glass_at_glass_depth;
  report["run"] = run_dir;
  report["config_file"] =
      options.config_file.empty() ? nlohmann::json() : nlohmann::json(options.config_file);
  report["datasets"] = nlohmann::json::array();
  for (const std::string& input : inputs) {
    TerminalProgress progress("demo: " + fs::path(input).filename().string(), std::nullopt);
    report["datasets"].push_back(InputInfo(input, {}, [&](int d, int) { progress.Update(d); }));
  }
  report["not_yet_built"] = {"loop closure"};

  std::ostringstream html;
  html << "<!doctype html><html><head><meta charset=\"utf-8\"><title>GlassFusion demo</title>"
          "<style>body{font-family:sans-serif;margin:2em;max-width:70em}td,th{padding:4px 10px;"
          "border-bottom:1px solid #ccc;text-align:right}td:first-child,th:first-child{text-align:"
          "left}img{max-width:100%}</style></head><body><h1>GlassFusion demo</h1>";
  html << "<h2>Built-in glass scene</h2><p>A synthetic Kinect v1 capture of a table with frosted "
          "and clear glass, shiny metal and a matte black box ("
       << options.frames << " frames, "
       << static_cast<int>(1000.0 * synth_summary.seconds_per_frame)
       << " ms per frame to render), read back through the same path as a real capture. "
          "First frame: colour, depth, and the holes over the colour image (red: no return, "
          "blue: projector shadow, green: out of range).</p><img src=\"overview.png\">";
  html << "<h3>Sensor holes by material (ground truth labels)</h3><table><tr><th>material</th>"
          "<th>pixels</th><th>holes</th></tr>";
  for (int m = 0; m < 5; ++m)
    html << "<tr><td>" << synth::MaterialName(static_cast<synth::Material>(m)) << "</td><td>"
         << material_pixels[m] << "</td><td>"
         << Percent(material_pixels[m] ? static_cast<double>(material_holes[m]) / material_pixels[m]
                                       : 0)
         << "</td></tr>";
  html << "</table><p>These holes are what GlassFusion's stereo fill targets.</p>";
  html << "<h3>Tracking and stereo fill (<code>glassfusion reconstruct</code>)</h3><p>"
       << run.frames << " frames at " << static_cast<int>(run.fps) << " fps, " << run.keyframes
       << " keyframes, trajectory error (ATE) "
       << (ate.success ? std::to_string(ate.ate_rmse_m * 1000.0).substr(0, 4) + " mm" : "n/a")
       << ". "
       << (options.config_file.empty()
               ? std::string()
               : "Settings from <code>" + HtmlEscape(options.config_file) + "</code>. ")
       << "Keyframe holes filled by stereo, scored against the depth of what the colour camera "
          "sees (\"good\": within 3%):</p><table><tr><th>material</th><th>holes</th><th>filled"
          "</th><th>good</th><th>median error</th></tr>";
  for (int m = 0; m < 5; ++m)
    html << "<tr><td>" << synth::MaterialName(static_cast<synth::Material>(m)) << "</td><td>"
         << fill_holes[m] << "</td><td>"
         << Percent(fill_holes[m] ? double(fill_filled[m]) / fill_holes[m] : 0) << "</td><td>"
         << Percent(fill_holes[m] ? double(fill_good[m]) / fill_holes[m] : 0) << "</td><td>"
         << Percent(Median(fill_errors[m])) << "</td></tr>";
  html << "</table><p>Filled clear-glass pixels that take the glass's depth instead of the "
          "background's (within 2% of the glass, more than 5% off the background; the goal is "
          "none): "
       << clear_glass_at_glass_depth << " of " << fill_filled[clear_glass] << ".</p>";
  if (!overlay_ts.empty())
    html << "<p>Keyframe " << overlay_ts
         << ": filled pixels green (cyan: carried from earlier keyframes; brighter = more "
            "confident), "
            "holes left empty magenta.</p><img src=\"fill_overlay.png\">";
  html << "<p>The run's surfel map is <code>run/map.ply</code>; <code>glassfusion compare</code> "
          "measures it with and without the fill. Loop closure is not built yet.</p>";
  if (!inputs.empty()) {
    html << "<h2>Datasets found under <code>" << HtmlEscape(data_dir) << "</code></h2>"
         << "<table><tr><th>input</th><th>kind</th><th>frames</th><th>size</th><th>depth</th>"
            "<th>holes</th><th>no return</th><th>shadow</th><th>out of range</th></tr>";
    for (const auto& j : report["datasets"]) {
      html << "<tr><td>" << HtmlEscape(fs::path(j["input"].get<std::string>()).filename().string())
           << "</td><td>" << j["source"].get<std::string>() << "</td><td>" << j["frames"]
           << "</td><td>" << j["width"] << "x" << j["height"] << "</td><td>"
           << j["depth_convention"].get<std::string>() << "</td><td>" << Percent(j["hole_fraction"])
           << "</td><td>" << Percent(j["holes"]["no_return"]) << "</td><td>"
           << Percent(j["holes"]["shadow"]) << "</td><td>" << Percent(j["holes"]["out_of_range"])
           << "</td></tr>";
    }
    html << "</table>";
  }
  html << "</body></html>\n";
  WriteTextFileAtomically((fs::path(options.out_dir) / "report.json").string(),
                          report.dump(2) + "\n");
  WriteTextFileAtomically((fs::path(options.out_dir) / "report.html").string(), html.str());
  std::cout << "demo: glass-table " << synth_summary.BriefReport() << "; report in "
            << (fs::path(options.out_dir) / "report.html").string() << std::endl;
}

}  // namespace gf
