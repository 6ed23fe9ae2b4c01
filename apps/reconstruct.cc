#include "apps/reconstruct.h"

#include <spdlog/spdlog.h>

#include <charconv>
#include <filesystem>

#include "acquisition/errors.h"
#include "apps/interrupt.h"
#include "apps/progress.h"
#include "pipeline/run_sink.h"
#include "report/run_report.h"
#include "surfels/mesh.h"
#include "surfels/ply.h"
#include "acquisition/bounds.h"

namespace fs = std::filesystem;

namespace gf {

bool ReconstructOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.Require(!input.empty(), "INPUT: the capture to reconstruct")
      .Require(!out_dir.empty(), "--out: the run folder")
      .Part("source", source)
      .Part("settings", pipeline);
  return c.ok();
}

void ParseFrameRange(const std::string& range, int* first, int* end) {
  // An empty range, or ":" with neither end, names no frames: the whole capture is had by leaving
  // --frames out, never by a range that says nothing.
  if (range.empty() || range == ":")
    throw InputError("--frames", "\"" + range + "\" names no frames: give N, A:B or A:");
  const size_t colon = range.find(':');
  // Whole numbers only: "1e3" must not silently read as 1.
  auto number = [&](const std::string& text, int if_empty) {
    if (text.empty()) return if_empty;
    int value = 0;
    const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || ptr != text.data() + text.size() || value < 0)
      throw InputError("--frames", "\"" + range + "\" is not A:B with whole frame numbers");
    return value;
  };
  if (colon == std::string::npos) {  // "N": the first N frames
    *first = 0;
    *end = number(range, -1);
    if (*end <= 0) throw InputError("--frames", "\"" + range + "\" needs N >= 1 frames");
    return;
  }
  *first = number(range.substr(0, colon), 0);
  *end = number(range.substr(colon + 1), -1);
  if (*end >= 0 && *end <= *first)
    throw InputError("--frames", "\"" + range + "\" needs 0 <= A < B");
}

int FrameCountOf(const std::string& range, const std::string& command) {
  int first = 0, end = -1;
  ParseFrameRange(range, &first, &end);
  if (first != 0 || end < 0)
    throw InputError("--frames",
                     command + " starts at frame 0: give N or 0:N, not \"" + range + "\"");
  return end;
}

ReconstructionSummary RunPipeline(
    const ReconstructOptions& options, FrameSource* source, RunSink* sink, RunSink* without_fill,
    const std::string& label,
    const std::function<void(const nlohmann::ordered_json& report)>& finish) {
  ReconstructionOptions pipeline = options.pipeline;
  pipeline.allow_lost = options.allow_lost;
  pipeline.input_path = options.input;
  pipeline.config_file = options.config_file;
  if (!options.source.camera_file.empty())
    pipeline.camera_file = options.source.camera_file;
  else if (fs::is_directory(options.input))
    pipeline.camera_file = (fs::path(options.input) / "camera.json").string();
  Reconstruction reconstruction(pipeline);
  TerminalProgress progress(label, source->FrameCount());
  ReconstructionCallbacks callbacks;
  callbacks.progress = [&](const ReconstructionProgress& p) {
    // After the last frame, what is still finishing.
    std::string detail;
    if (p.tracking_done) {
      detail = "finishing:";
      if (pipeline.fill)
        detail += " fill " + std::to_string(p.keyframes_filled) + "/" +
                  std::to_string(p.keyframes_offered) + " keyframes,";
      if (pipeline.loop_closure)
        detail += " loop search " + std::to_string(p.keyframes_searched) + " keyframes,";
      if (pipeline.fusion) detail += " fused " + std::to_string(p.frames_fused) + " frames,";
      detail.pop_back();
    }
    progress.SetTotal(p.total);
    progress.Update(p.frames, detail);
  };
  callbacks.stop = [&]() -> std::string {
    if (!options.interrupt || !*options.interrupt) return "";
    return "interrupted by " + SignalName(*options.interrupt);
  };
  callbacks.finish = finish;
  const ReconstructionSummary s = reconstruction.Run(*source, sink, callbacks, without_fill);
  progress.Finish();
  if (s.refused) throw InputError(options.input, s.stopped_because);
  if (!s.complete)
    throw Interrupted(options.interrupt ? options.interrupt->load() : 0,
                      options.out_dir + ": " + s.stopped_because + " during " + s.stopped_during +
                          " after " + std::to_string(s.frames) +
                          " frames; partial run written (\"complete\": false)");
  return s;
}

ReconstructionSummary RunReconstruct(const ReconstructOptions& options) {
  std::string problem;
  if (!options.Check(&problem)) throw InputError(options.out_dir, "bad options: " + problem);
  // The input first: a bad input leaves no run folder behind.
  std::unique_ptr<FrameSource> source = OpenFrameSource(options.input, options.source);
  RunFolder::Options folder;
  folder.earlier = options.force ? RunFolder::kReplace : RunFolder::kRefuse;
  folder.inputs = {options.input};
  FolderRunSink sink(options.out_dir, folder);
  // Before the final report.json: the mesh and the page (a failure of either is a warning in it).
  auto finish = [&](const nlohmann::ordered_json& report) {
    if (options.mesh && options.pipeline.fusion) {
      try {
        const MeshSummary m = WriteMapMesh(
            ReadSurfelPly((fs::path(options.out_dir) / "map.ply").string()), sink.File("mesh.ply"),
            {});
        spdlog::info("{}", m.BriefReport());
      } catch (const std::exception& e) {
        throw std::runtime_error(options.out_dir + "/mesh.ply not written: " + e.what());
      }
    }
    try {
      sink.File("report.html");
      WriteRunReport(options.out_dir, options.input, report,
                     [&](const std::string& name) { return sink.File(name); });
    } catch (const std::exception& e) {
      throw std::runtime_error(options.out_dir + "/report.html not written: " + e.what());
    }
  };
  return RunPipeline(options, source.get(), &sink, nullptr, "reconstruct", finish);
}

}  // namespace gf
