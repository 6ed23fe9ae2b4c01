#include "apps/commands.h"

#include <cstdio>
#include <iostream>

#include "acquisition/errors.h"
#include "acquisition/input_info.h"
#include "acquisition/json_text.h"
#include "acquisition/trajectory_metrics.h"
#include "apps/capture.h"
#include "apps/frame_range.h"
#include "apps/interrupt.h"
#include "apps/progress.h"
#include "datasets/synth.h"
#include "eval/map_truth.h"
#include "fill/colmap_workspace.h"
#include "pipeline/settings.h"
#include "runs/bench.h"
#include "runs/compare.h"
#include "runs/demo.h"
#include "runs/reconstruct.h"

namespace gf {
namespace {

// Options every command that reads an INPUT shares.
struct InputArgs {
  std::string input;
  std::string camera_file;
  std::string depth_folder;
  std::string depth_topic;
  std::string color_topic;
  FrameSourceOptions ToOptions() const {
    FrameSourceOptions o;
    o.camera_file = camera_file;
    o.depth_folder = depth_folder;
    o.bag_depth_topic = depth_topic;
    o.bag_color_topic = color_topic;
    return o;
  }
};

void AddInputArgs(CLI::App* cmd, InputArgs* args) {
  cmd->add_option("INPUT", args->input,
                  "TUM folder, Redwood folder, raw Kinect folder (*.pgm / fakenect INDEX.txt), "
                  ".oni file, RealSense .bag, or device: dummy, openni2[:URI], freenect[:INDEX]")
      ->required();
  cmd->add_option("--camera", args->camera_file, "camera.json to use instead of INPUT/camera.json");
  cmd->add_option("--depth-dir", args->depth_folder,
                  "Redwood: depth subfolder (default depth/, else depth_noisy/)");
  cmd->add_option("--depth-topic", args->depth_topic,
                  "RealSense .bag with several depth streams: the one to read, e.g. "
                  "/device_0/sensor_0/Depth_0/image/data");
  cmd->add_option("--color-topic", args->color_topic,
                  "RealSense .bag with several colour streams: the one to read");
}

// --print-config: every setting as the JSON --config reads (with --config FILE applied when it
// comes first), then exit 0. Runs while parsing, so that INPUT and --out are not needed.
void AddPrintConfig(CLI::App* cmd, const std::string* config_file,
                    const ReconstructionOptions* pipeline) {
  cmd->add_flag_callback(
      "--print-config",
      [config_file, pipeline] {
        ReconstructionOptions o = *pipeline;
        if (!config_file->empty()) ApplyConfigFile(*config_file, &o);
        std::cout << JsonText(SettingsToJson(o)) << std::endl;
        throw CLI::Success();
      },
      "print every setting as the JSON --config reads (after --config FILE) and exit");
}

void AddInfoCommand(CLI::App& app) {
  auto args = std::make_shared<InputArgs>();
  CLI::App* cmd = app.add_subcommand(
      "info",
      "print JSON about INPUT: source kind, frames, size, intrinsics, depth convention, "
      "hole fraction");
  cmd->footer(
      "Example: glassfusion info tum_fr1_xyz\nWrites: JSON on stdout (source kind, frames, size, "
      "intrinsics, depth convention, hole fraction by class, median depth, warnings).");
  AddInputArgs(cmd, args.get());
  cmd->callback([args] {
    TerminalProgress progress("info", std::nullopt);
    const auto info =
        InputInfo(args->input, args->ToOptions(), [&](int done, int) { progress.Update(done); });
    progress.Finish();
    for (const auto& w : info["warnings"])
      std::fprintf(stderr, "warning: %s: %s\n", args->input.c_str(), w.get<std::string>().c_str());
    std::cout << JsonText(info) << std::endl;
  });
}

void AddSynthCommand(CLI::App& app) {
  auto options = std::make_shared<synth::SynthOptions>();
  auto out = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "synth", "render a synthetic Kinect v1 glass scene with ground truth into a TUM folder");
  cmd->footer(
      "Example: glassfusion synth --scene shelf --frames 30 --seed 6 --out shelf6\nWrites: "
      "OUT/rgb, depth, raw (Kinect v1 11-bit PGM), rgb.txt, depth.txt, camera.json, "
      "groundtruth.txt, gt/ (true depth, materials), scene.ply.");
  cmd->add_option("--scene", options->scene, "glass-table, shelf, window or bottles")
      ->capture_default_str();
  auto frames = std::make_shared<std::string>(std::to_string(options->frames));
  cmd->add_option("--frames", *frames, "frames to render: N (or 0:N)")->capture_default_str();
  cmd->add_option("--seed", options->seed, "textures, trajectory and noise")->capture_default_str();
  cmd->add_flag("--loop", options->loop, "trajectory comes back to its start");
  auto motion = std::make_shared<std::string>(synth::MotionName(options->motion));
  cmd->add_option("--motion", *motion,
                  "orbit (sideways), vertical, diagonal or forward, looking at the scene")
      ->capture_default_str();
  cmd->add_option("--degrees-per-frame", options->degrees_per_frame,
                  "speed: this arc of the orbit per frame (0.6: about 1.6 cm, 0.48 m/s)")
      ->capture_default_str();
  cmd->add_option("--out", *out, "folder to create")->required();
  cmd->callback([options, out, frames, motion] {
    options->frames = FrameCountOf(*frames, "synth");
    if (!synth::ParseMotion(*motion, &options->motion))
      throw InputError("--motion",
                       "\"" + *motion + "\" is not orbit, vertical, diagonal or forward");
    TerminalProgress progress("synth", options->frames);
    const synth::SynthSummary s =
        synth::GenerateDataset(*options, *out, [&](int done, int) { progress.Update(done); });
    progress.Finish();
    std::cout << "synth: " << s.BriefReport() << "; written to " << *out << std::endl;
  });
}

constexpr const char* kNoGlassHelp =
    "no transparent surfels: clear glass that the sensor both reads and sees through is treated "
    "as any surface (the setting glass.enabled)";

void AddReconstructCommand(CLI::App& app) {
  auto options = std::make_shared<ReconstructOptions>();
  auto args = std::make_shared<InputArgs>();
  auto range = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "reconstruct",
      "track the camera through INPUT and fill keyframe depth holes by stereo; write "
      "DIR/trajectory.txt, map.ply, keyframes/, undistorted/, camera.json, report.json and "
      "report.html");
  cmd->footer(
      "Example: glassfusion reconstruct tum_fr1_xyz --out run --frames 0:300\nWrites: "
      "DIR/trajectory.txt (TUM), map.ply (surfels), keyframes/ (hole masks, filled depth, "
      "overlays), undistorted/ (the keyframes on the pinhole camera, with Open3D's "
      "camera_intrinsic.json and trajectory.log), camera.json, report.json, report.html; --mesh "
      "also mesh.ply.");
  AddInputArgs(cmd, args.get());
  cmd->add_option("--out", options->out_dir, "run folder")->required();
  CLI::Option* frames = cmd->add_option(
      "--frames", *range, "frames A:B (A included, B excluded), A: from A, or N the first N");
  auto no_fill = std::make_shared<bool>(false);
  cmd->add_flag("--no-fill", *no_fill, "no stereo hole filling of keyframes (sensor depth only)");
  auto no_fusion = std::make_shared<bool>(false);
  cmd->add_flag("--no-fusion", *no_fusion, "no surfel map (map.ply)");
  auto no_loops = std::make_shared<bool>(false);
  cmd->add_flag("--no-loop-closure", *no_loops,
                "no loop closure, pose graph or relocalisation (poses as tracked)");
  cmd->add_flag("--mesh", options->mesh,
                "also mesh.ply: a triangle mesh of the map (PCL greedy projection)");
  cmd->add_flag("--frame-to-model", options->pipeline.frame_to_model,
                "refine each frame's pose against the surfel map of the frames before it "
                "(after aligning it to its keyframe)");
  auto sweep_all = std::make_shared<bool>(false);
  cmd->add_flag("--sweep-all", *sweep_all,
                "plane-sweep every keyframe pair (default: rectified SGBM for sideways pairs, "
                "then the sweep over the holes it left; the sweep alone for forward ones)");
  cmd->add_option("--config", options->config_file,
                  "JSON file of tracker and fill settings (the tree report.json lists under "
                  "config.settings; any part of it)");
  AddPrintConfig(cmd, &options->config_file, &options->pipeline);
  cmd->add_flag("--force", options->force,
                "replace the earlier run in --out: remove only the files its marker "
                ".glassfusion-run lists (without it, a folder that is not empty is refused; a "
                "folder without the marker, or the input, is never replaced)");
  cmd->add_flag("--allow-lost", options->allow_lost,
                "accept a run that loses tracking on most frames (exit 0 with a warning)");
  auto no_glass = std::make_shared<bool>(false);
  cmd->add_flag("--no-glass", *no_glass, kNoGlassHelp);
  cmd->callback([options, args, range, frames, no_fill, no_fusion, no_loops, sweep_all,
                 no_glass] {
    if (!options->config_file.empty()) ApplyConfigFile(options->config_file, &options->pipeline);
    if (*no_glass) options->pipeline.fusion_options.fusion.glass.enabled = false;
    if (*sweep_all) options->pipeline.fill_options.stereo.plane_sweep_always = true;
    options->pipeline.fill = !*no_fill;
    options->pipeline.fusion = !*no_fusion;
    options->pipeline.loop_closure = !*no_loops;
    options->input = args->input;
    options->source = args->ToOptions();
    options->source.load_color = options->pipeline.tracker.use_features || options->pipeline.fill;
    if (frames->count() > 0)  // given, even as "": ParseFrameRange refuses a range of no frames
      ParseFrameRange(*range, &options->pipeline.first_frame, &options->pipeline.end_frame);
    const InterruptHandler interrupt;  // Ctrl-C: stop, write the partial run, exit 130
    options->interrupt = interrupt.signal();
    const ReconstructionSummary s = RunReconstruct(*options);
    for (const std::string& w : s.warnings)
      std::fprintf(stderr, "warning: %s: %s\n", options->input.c_str(), w.c_str());
    std::cout << "reconstruct: " << s.BriefReport() << "; outputs in " << options->out_dir
              << std::endl;
  });
}

void AddCompareCommand(CLI::App& app) {
  auto options = std::make_shared<ReconstructOptions>();
  auto args = std::make_shared<InputArgs>();
  auto range = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "compare",
      "track INPUT once and fuse it twice, with and without the stereo fill; write "
      "DIR/with_fill/, DIR/without_fill/ (run folders with map.ply), DIR/compare.json and "
      "DIR/report.html (completeness per material where INPUT has ground truth)");
  cmd->footer(
      "Example: glassfusion compare shelf6 --out cmp\nWrites: DIR/with_fill/ and DIR/without_fill/ "
      "(run folders), DIR/compare.json, DIR/report.html.");
  AddInputArgs(cmd, args.get());
  cmd->add_option("--out", options->out_dir, "comparison folder")->required();
  CLI::Option* frames = cmd->add_option(
      "--frames", *range, "frames A:B (A included, B excluded), A: from A, or N the first N");
  cmd->add_option("--config", options->config_file, "JSON file of settings, as for reconstruct");
  AddPrintConfig(cmd, &options->config_file, &options->pipeline);
  cmd->add_flag("--force", options->force,
                "replace an earlier comparison in --out: remove only the files its marker "
                ".glassfusion-run lists");
  cmd->add_flag("--allow-lost", options->allow_lost,
                "accept a run that loses tracking on most frames");
  auto no_glass = std::make_shared<bool>(false);
  cmd->add_flag("--no-glass", *no_glass, kNoGlassHelp);
  cmd->callback([options, args, range, frames, no_glass] {
    if (!options->config_file.empty()) ApplyConfigFile(options->config_file, &options->pipeline);
    if (*no_glass) options->pipeline.fusion_options.fusion.glass.enabled = false;
    options->input = args->input;
    options->source = args->ToOptions();
    if (frames->count() > 0)
      ParseFrameRange(*range, &options->pipeline.first_frame, &options->pipeline.end_frame);
    const InterruptHandler interrupt;
    options->interrupt = interrupt.signal();
    const CompareSummary s = RunCompare(*options);
    std::cout << "compare: " << s.BriefReport() << "; " << options->out_dir << "/report.html"
              << std::endl;
  });
}

// bench's end-to-end row, spelt out: CPU seconds per stage, cores used, memory added.
void PrintEndToEnd(const nlohmann::ordered_json& e) {
  const auto& cpu = e["cpu_seconds"];
  std::printf("end to end: %.1f frames/s, %d keyframes; CPU seconds:", e["fps"].get<double>(),
              e["keyframes"].get<int>());
  for (const auto& [stage, seconds] : cpu.items())
    if (stage != "cores_used" && stage != "cores")
      std::printf(" %s %.1f", stage.c_str(), seconds.get<double>());
  std::printf("; %.2f of %d cores busy; %.0f MiB added at peak\n", cpu["cores_used"].get<double>(),
              cpu["cores"].get<int>(), e["peak_added_mib"].get<double>());
}

void AddBenchCommand(CLI::App& app) {
  auto options = std::make_shared<BenchOptions>();
  auto args = std::make_shared<InputArgs>();
  auto range = std::make_shared<std::string>();
  auto no_peers = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "bench", "time GlassFusion's tracker and OpenCV's odometry peers on the same frames");
  cmd->footer(
      "Example: glassfusion bench tum_fr1_xyz_head --fill-every 3\nWrites: a table and JSON on "
      "stdout: ms per frame, fps and ATE per method, the machine's cores, the loop stage's cost.");
  AddInputArgs(cmd, args.get());
  CLI::Option* frames = cmd->add_option(
      "--frames", *range, "frames A:B (A included, B excluded), A: from A, or N the first N");
  cmd->add_option("--gt", options->gt, "ground truth (default: INPUT/groundtruth.txt or .log)");
  cmd->add_flag("--no-peers", *no_peers, "time GlassFusion only");
  cmd->add_option("--fill-every", options->fill_every,
                  "also time stereo hole filling on one core, every K-th frame a keyframe, paired "
                  "and filled as reconstruct does with the tracked poses (0: off)");
  cmd->add_flag("--frame-to-model", options->frame_to_model,
                "also our tracker refined against the surfel map of the frames before each one");
  auto no_loops = std::make_shared<bool>(false);
  cmd->add_flag("--no-loop-closure", *no_loops,
                "leave out the row of our tracking with loop closure and the loop stage's cost");
  auto no_end_to_end = std::make_shared<bool>(false);
  cmd->add_flag("--no-end-to-end", *no_end_to_end,
                "leave out the whole reconstruction (fill, fusion, loop closure) end to end");
  cmd->add_flag("--fusion", options->fusion,
                "also time the surfel fusion per frame on one core and on two, and with a map "
                "of about a million surfels");
  auto config = std::make_shared<std::string>();
  cmd->add_option("--config", *config,
                  "JSON file of tracker and fill settings, as for reconstruct");
  AddPrintConfig(cmd, config.get(), &options->pipeline);
  cmd->callback([options, args, range, frames, no_peers, no_loops, no_end_to_end, config] {
    if (!config->empty()) ApplyConfigFile(*config, &options->pipeline);
    options->input = args->input;
    options->source = args->ToOptions();
    options->peers = !*no_peers;
    options->loop_closure = !*no_loops;
    options->end_to_end = !*no_end_to_end;
    if (frames->count() > 0) ParseFrameRange(*range, &options->first_frame, &options->end_frame);
    const auto j = RunBench(*options);
    std::printf("%-36s %8s %8s %10s %8s\n", "method", "ms", "fps", "ATE (cm)", "failed");
    for (const auto& m : j["methods"]) {
      const bool has_ate = m.contains("ate_rmse_m") && !m["ate_rmse_m"].is_null();
      std::printf("%-36s %8.1f %8.1f %10s %8d\n", m["method"].get<std::string>().c_str(),
                  m["median_ms"].get<double>(), m["fps"].get<double>(),
                  has_ate
                      ? std::to_string(100.0 * m["ate_rmse_m"].get<double>()).substr(0, 6).c_str()
                      : "-",
                  m["failed_frames"].get<int>());
    }
    if (j.contains("stereo_fill") && j["stereo_fill"]["pairs"].get<int>() > 0) {
      const auto& f = j["stereo_fill"];
      std::printf(
          "stereo fill, one core: %d pairs, median %.1f ms/pair (max %.1f) after "
          "%.1f ms pair selection, then %.1f ms carrying earlier keyframes' fills, %.1f%% of "
          "hole pixels filled (%.1f%% with the carried fills); OpenCV StereoSGBM "
          "alone: %s ms on %d sideways pairs\n",
          f["pairs"].get<int>(), f["median_ms"].get<double>(), f["max_ms"].get<double>(),
          f["pair_selection_median_ms"].get<double>(), f["carry_median_ms"].get<double>(),
          100.0 * f["fill_rate"].get<double>(), 100.0 * f["fill_rate_with_carry"].get<double>(),
          f["opencv_sgbm_median_ms"].is_null()
              ? "-"
              : std::to_string(f["opencv_sgbm_median_ms"].get<double>()).substr(0, 6).c_str(),
          f["opencv_sgbm_pairs"].get<int>());
    }
    if (j.contains("end_to_end")) PrintEndToEnd(j["end_to_end"]);
    std::printf("%d frames, %u cores\n", j["frames"].get<int>(), j["cores"].get<unsigned>());
    std::cout << JsonText(j) << std::endl;
  });
}

void AddEvalCommand(CLI::App& app) {
  auto gt = std::make_shared<std::string>();
  auto est = std::make_shared<std::string>();
  auto options = std::make_shared<TrajectoryErrorOptions>();
  CLI::App* cmd = app.add_subcommand(
      "eval", "trajectory error of --est against --gt as JSON (ATE after rigid alignment, RPE)");
  cmd->footer(
      "Example: glassfusion eval --gt cap/groundtruth.txt --est run/trajectory.txt\nWrites: JSON "
      "on stdout (ATE, RPE; with --map and --gt-mesh, accuracy and completeness per material).");
  cmd->add_option("--gt", *gt, "ground truth: TUM text or Redwood .log")->required();
  cmd->add_option("--est", *est, "estimate: TUM text or Redwood .log")->required();
  cmd->add_option("--max-dt", options->max_dt, "association window, seconds")
      ->capture_default_str();
  auto map = std::make_shared<std::string>();
  auto mesh = std::make_shared<std::string>();
  cmd->add_option("--map", *map, "map.ply of the run whose trajectory --est is");
  cmd->add_option("--gt-mesh", *mesh,
                  "ground-truth mesh (a synthetic capture's scene.ply): the map's accuracy and "
                  "completeness, overall and per material");
  cmd->callback([gt, est, options, map, mesh] {
    if (map->empty() != mesh->empty()) throw InputError("--map", "needs --gt-mesh too");
    std::string problem;
    if (!options->Check(&problem)) throw InputError("--max-dt", problem);
    const TrajectoryErrorSummary s =
        EvaluateTrajectory(ReadTrajectory(*gt), ReadTrajectory(*est), *options);
    if (!s.success) throw InputError(*est, s.message + " with " + *gt);
    nlohmann::ordered_json j;
    j["gt"] = *gt;
    j["est"] = *est;
    j["pairs"] = s.pairs;
    j["ate_rmse_m"] = s.ate_rmse_m;
    j["ate_mean_m"] = s.ate_mean_m;
    j["ate_median_m"] = s.ate_median_m;
    j["ate_max_m"] = s.ate_max_m;
    j["rpe_trans_rmse_m"] = s.rpe_trans_rmse_m;
    j["rpe_rot_rmse_deg"] = s.rpe_rot_rmse_deg;
    // The rigid alignment fits 6 parameters to 3 coordinates per pose: with few poses it
    // absorbs much of the error (a fifth with 10, half with 4), and the ATE looks too good.
    constexpr int kFewPairs = 10;
    nlohmann::ordered_json warnings = nlohmann::ordered_json::array();
    if (s.pairs < kFewPairs) {
      warnings.push_back("only " + std::to_string(s.pairs) +
                         " poses associated: the ATE after alignment is not meaningful with "
                         "fewer than " +
                         std::to_string(kFewPairs));
      std::fprintf(stderr, "warning: %s: %s\n", est->c_str(),
                   warnings.back().get<std::string>().c_str());
    }
    j["warnings"] = warnings;
    if (!map->empty()) {
      const nlohmann::ordered_json m =
          EvaluateMapFiles(*map, *mesh, ReadTrajectory(*gt), ReadTrajectory(*est));
      j["map"] = *map;
      j["completeness"] = m["completeness"];
      j["accuracy"] = m["accuracy"];
    }
    std::cout << JsonText(j) << std::endl;
  });
}

void AddCaptureCommand(CLI::App& app) {
  auto options = std::make_shared<CaptureOptions>();
  CLI::App* cmd = app.add_subcommand(
      "capture", "record a device (or a .oni, .bag or .mkv recording) to a TUM-format folder");
  cmd->footer(
      "Example: glassfusion capture --device freenect --out cap --frames 300\nWrites: OUT as a TUM "
      "folder (rgb/, depth/, rgb.txt, depth.txt, camera.json).");
  cmd->add_option("--device", options->device,
                  "dummy (OpenNI2's software device), openni2[:URI], freenect[:INDEX], or a "
                  "recording: FILE.oni, FILE.bag, FILE.mkv")
      ->required();
  cmd->add_option("--out", options->out_dir, "TUM folder to create")->required();
  auto frames = std::make_shared<std::string>();
  CLI::Option* frames_option =
      cmd->add_option("--frames", *frames,
                      "frames to record: N (or 0:N); default until the end or "
                      "Ctrl-C");
  cmd->add_option("--camera", options->camera_file, "camera.json to use instead of the device's");
  cmd->callback([options, frames, frames_option] {
    if (frames_option->count() > 0) options->frames = FrameCountOf(*frames, "capture");
    RunCapture(*options);
  });
}

void AddColmapExportCommand(CLI::App& app) {
  auto run_dir = std::make_shared<std::string>();
  auto workspace = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "colmap-export",
      "write a COLMAP workspace (images/, sparse/0/ text model with the tracked keyframe poses) "
      "from a reconstruct run");
  cmd->footer(
      "Example: glassfusion colmap-export run --out ws\nWrites: WS/images/ (the keyframes' colour, "
      "as the input's camera saw it) and WS/sparse/0/ (cameras.txt: one FULL_OPENCV camera with "
      "the input's distortion; images.txt: the keyframe poses; points3D.txt empty).");
  cmd->add_option("RUN_DIR", *run_dir, "folder written by `glassfusion reconstruct`")->required();
  cmd->add_option("--out", *workspace, "workspace folder to create")->required();
  cmd->callback([run_dir, workspace] {
    const ColmapExportSummary s = RunColmapExport(*run_dir, *workspace);
    std::cout << "colmap-export: " << s.BriefReport() << " in " << *workspace << std::endl;
  });
}

void AddColmapImportCommand(CLI::App& app) {
  auto workspace = std::make_shared<std::string>();
  auto run_dir = std::make_shared<std::string>();
  auto options = std::make_shared<ColmapImportOptions>();
  CLI::App* cmd = app.add_subcommand(
      "colmap-import",
      "read COLMAP's refined poses (text model) and patch_match_stereo depth maps back into a "
      "run: RUN_DIR/trajectory_colmap.txt, holes filled in keyframes/, colmap_import.json");
  cmd->footer(
      "Example: glassfusion colmap-import ws --into run\nWrites: COLMAP's refined poses and depth "
      "maps into the run folder.");
  cmd->add_option("WORKSPACE", *workspace, "COLMAP workspace made by colmap-export")->required();
  cmd->add_option("--into", *run_dir, "the reconstruct run folder")->required();
  cmd->add_option("--model", options->model_dir,
                  "text model with refined poses (default WORKSPACE/refined)");
  cmd->callback([workspace, run_dir, options] {
    const ColmapImportSummary s = RunColmapImport(*workspace, *run_dir, *options);
    std::cout << "colmap-import: " << s.BriefReport() << std::endl;
  });
}

void AddDemoCommand(CLI::App& app) {
  auto options = std::make_shared<DemoOptions>();
  CLI::App* cmd = app.add_subcommand(
      "demo", "generate the built-in glass scene, measure its holes, write OUT/report.html");
  cmd->footer(
      "Example: glassfusion demo --out demo-out\nWrites: OUT/report.html and the runs it shows.");
  cmd->add_option("--out", options->out_dir, "output folder")->capture_default_str();
  auto frames = std::make_shared<std::string>(std::to_string(options->frames));
  cmd->add_option("--frames", *frames, "frames of the glass scene: N (or 0:N)")
      ->capture_default_str();
  cmd->add_option("--data", options->data_dir,
                  "folder of datasets to summarise too (default ../shared/datasets if present)");
  cmd->add_option("--config", options->config_file,
                  "JSON file of tracker and fill settings for the reconstruction, as for "
                  "reconstruct");
  auto no_glass = std::make_shared<bool>(false);
  cmd->add_flag("--no-glass", *no_glass, kNoGlassHelp);
  cmd->callback([options, frames, no_glass] {
    options->glass = !*no_glass;
    options->frames = FrameCountOf(*frames, "demo");
    std::cout << "demo: " << RunDemo(*options) << std::endl;
  });
}

}  // namespace

void RegisterCommands(CLI::App& app) {
  AddInfoCommand(app);
  AddSynthCommand(app);
  AddReconstructCommand(app);
  AddCompareCommand(app);
  AddBenchCommand(app);
  AddEvalCommand(app);
  AddCaptureCommand(app);
  AddColmapExportCommand(app);
  AddColmapImportCommand(app);
  AddDemoCommand(app);
  AddBatchCommand(app);
  AddFillFrameCommand(app);
}

}  // namespace gf
