#include "runs/reconstruct.h"

#include <spdlog/spdlog.h>

#include <filesystem>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"
#include "acquisition/progress.h"
#include "acquisition/run_layout.h"
#include "pipeline/run_reader.h"
#include "pipeline/run_sink.h"
#include "report/run_report.h"
#include "surfels/mesh.h"

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

ReconstructionSummary RunPipeline(
    const ReconstructOptions& options, FrameSource* source, RunSink* sink, RunSink* without_fill,
    const std::string& label,
    const std::function<void(const RunReport& report)>& finish) {
  ReconstructionOptions pipeline = options.pipeline;
  pipeline.allow_lost = options.allow_lost;
  pipeline.input_path = options.input;
  pipeline.config_file = options.config_file;
  if (!options.source.camera_file.empty())
    pipeline.camera_file = options.source.camera_file;
  else if (fs::is_directory(options.input))
    pipeline.camera_file = (fs::path(options.input) / "camera.json").string();
  Reconstruction reconstruction(pipeline);
  const std::unique_ptr<Progress> progress = ShowProgress(label, source->FrameCount());
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
    progress->SetTotal(p.total);
    progress->Update(p.frames, detail);
  };
  callbacks.stop = [&]() -> std::string {
    if (!options.interrupt || !*options.interrupt) return "";
    return "interrupted by " + SignalName(*options.interrupt);
  };
  callbacks.finish = finish;
  const ReconstructionSummary s = reconstruction.Run(*source, sink, callbacks, without_fill);
  progress->Finish();
  if (s.refused) throw InputError(options.input, s.stopped_because);
  if (!s.complete)
    throw Interrupted(options.interrupt ? options.interrupt->load() : 0,
                      options.out_dir + ": " + s.stopped_because + " during " + s.stopped_during +
                          " after " + std::to_string(s.frames) +
                          " frames; partial run written (\"complete\": false)");
  return s;
}

std::unique_ptr<FrameSource> OpenRunInput(const ReconstructOptions& options,
                                          RunFolder::Options* folder) {
  std::string problem;
  if (!options.Check(&problem)) throw InputError(options.out_dir, "bad options: " + problem);
  std::unique_ptr<FrameSource> source = OpenFrameSource(options.input, options.source);
  folder->earlier = options.force ? RunFolder::kReplace : RunFolder::kRefuse;
  folder->inputs = {options.input};
  return source;
}

ReconstructionSummary RunReconstruct(const ReconstructOptions& options) {
  RunFolder::Options folder;
  std::unique_ptr<FrameSource> source = OpenRunInput(options, &folder);
  FolderRunSink sink(options.out_dir, folder);
  // Before the final report.json: the mesh and the page (a failure of either is a warning in it).
  const RunLayout layout(options.out_dir);
  auto finish = [&](const RunReport& report) {
    if (options.mesh && options.pipeline.fusion) {
      try {
        const MeshSummary m = WriteMapMesh(
            RunReader(options.out_dir).Map(),
            sink.File(RunLayout::kMesh),
            {});
        spdlog::info("{}", m.BriefReport());
      } catch (const std::exception& e) {
        throw std::runtime_error(layout.Path(RunLayout::kMesh) + " not written: " + e.what());
      }
    }
    try {
      sink.File(RunLayout::kPage);
      WriteRunReport(options.out_dir, options.input, report,
                     [&](const std::string& name) { return sink.File(name); });
    } catch (const std::exception& e) {
      throw std::runtime_error(layout.Path(RunLayout::kPage) + " not written: " + e.what());
    }
  };
  return RunPipeline(options, source.get(), &sink, nullptr, "reconstruct", finish);
}

}  // namespace gf
