#include "pipeline/reconstruction.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <thread>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"
#include "pipeline/map_completion.h"
#include "pipeline/settings.h"
#include "pipeline/stages.h"
#include "pipeline/timing.h"

namespace gf {
namespace {

using Clock = std::chrono::steady_clock;

// report.json (DESIGN.md's keys), from the stages' reports.
RunReport MakeReport(const ReconstructionOptions& options, const FrameSource& source,
                     const TrackingRecord& tracking, const FillStage* fill,
                     const FusionStage* fusion, const LoopClosureStage* loop,
                     const ReconstructionSummary& summary) {
  RunReport report;
  report.complete = summary.complete;
  report.stopped_because = summary.stopped_because;
  report.stopped_during = summary.stopped_during;
  report.input = {options.input_path.empty() ? source.Input() : options.input_path,
                  source.Kind(), options.first_frame, options.end_frame};
  RunConfigReport& c = report.config;
  c.tracker = options.frame_to_model && options.fusion ? "frame_to_keyframe_then_model_icp"
                                                        : "frame_to_keyframe_icp";
  c.stereo_fill = options.fill;
  c.surfel_fusion = options.fusion;
  c.loop_closure = options.loop_closure;
  c.threads = std::string("reader + tracker") + (options.fill ? " + stereo" : "") +
              (options.fusion ? " + fusion" : "") + (options.loop_closure ? " + loop closure" : "");
  c.hardware_concurrency = std::thread::hardware_concurrency();
  if (!options.config_file.empty()) c.file = options.config_file;
  c.settings = SettingsToJson(options);
  report.frames = summary.frames;
  report.fps = summary.fps;
  report.seconds = summary.seconds;
  auto& steps = report.stages.steps;
  steps = {{"read", StepTimes::Of(tracking.read_ms)}, {"track", StepTimes::Of(tracking.track_ms)}};
  if (fill) {
    report.fill = fill->Report();
    std::vector<double> stereo_ms;  // per keyframe: stereo, validation and carry
    for (const KeyframeFill& k : report.fill->per_keyframe)
      if (!k.partner.empty()) stereo_ms.push_back(k.ms);
    steps.push_back({"stereo", StepTimes::Of(stereo_ms)});
  }
  if (fusion) {
    report.surfels = fusion->Report();
    steps.push_back({"fusion", report.surfels->frame_ms});
    steps.push_back({"fusion_fill", report.surfels->fill_ms});
  }
  if (loop) {
    report.loops = loop->Report();
    steps.push_back({"loop_closure", report.loops.keyframe_ms});
  }
  report.keyframes = summary.keyframes;
  constexpr size_t kListed = 1000;  // lost frames named in the report at most
  report.tracking = {summary.lost, tracking.relocalised, tracking.restarted,
                     std::vector<std::string>(
                         tracking.lost_frames.begin(),
                         tracking.lost_frames.begin() +
                             static_cast<long>(std::min(kListed, tracking.lost_frames.size())))};
  report.warnings = summary.warnings;
  return report;
}

std::string Describe(const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const std::exception& e) {
    return e.what();
  } catch (...) {
    return "unknown error";
  }
}

}  // namespace

bool ReconstructionOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.In("first_frame", first_frame, 0, kMaxCaptureFrames, kMoreFramesThanACapture)
      .Require(end_frame < 0 || end_frame > first_frame,
               "end_frame must be more than first_frame (or negative: to the end)")
      .In("queue_capacity", queue_capacity, 1, kMaxFramesInMemory, kMoreFramesThanMemory)
      .Part("tracker", tracker);
  if (fill) c.Part("fill", fill_options);
  if (fusion) c.Part("fusion", fusion_options);
  if (loop_closure) c.Part("loop_closure", loop_options);
  return c.ok();
}

std::string ReconstructionSummary::BriefReport() const {
  char buffer[240];
  std::snprintf(buffer, sizeof(buffer),
                "%s%d frames in %.1f s (%.1f fps), %d keyframes, %d lost, %d loops, %ld of %ld "
                "keyframe hole pixels filled, %ld surfels",
                complete ? "" : "stopped early: ", frames, seconds, fps, keyframes, lost, loops,
                filled_pixels, hole_pixels, surfels);
  return buffer;
}

Reconstruction::Reconstruction(ReconstructionOptions options) : options_(std::move(options)) {
  std::string problem;
  if (!options_.Check(&problem)) throw InputError("settings", problem);
}

// The stages of one run; destroyed in reverse order (each after those that use it).
struct Reconstruction::Stages {
  PoseCorrections corrections;
  std::unique_ptr<FusionStage> fusion;
  std::unique_ptr<FillStage> fill;
  std::unique_ptr<LoopClosureStage> loop;
  std::unique_ptr<BoundedQueue<FrameItem>> queue;
  std::unique_ptr<ReadStage> reader;
  std::unique_ptr<TrackStage> tracker;
};

namespace {

// The poses tracking gave, moved by the pose graph's corrections of their keyframes.
Trajectory CorrectedTrajectory(const TrackingRecord& tracking, const PoseCorrections& corrections) {
  const std::map<int, SE3> c = corrections.Snapshot();
  Trajectory out = tracking.trajectory;
  for (size_t i = 0; i < out.size(); ++i)
    out[i].world_from_camera =
        PoseCorrections::Lookup(c, tracking.keyframe[i]) * out[i].world_from_camera;
  return out;
}

// Runs `finish`, keeping the first error of the run.
void FinishStage(const std::function<void()>& finish, std::exception_ptr* error) {
  try {
    finish();
  } catch (...) {
    if (!*error) *error = std::current_exception();
  }
}

}  // namespace

std::unique_ptr<Reconstruction::Stages> Reconstruction::MakeStages(FrameSource& source,
                                                                   RunSink* sink,
                                                                   RunSink* without_fill,
                                                                   bool live) const {
  // spdlog builds its default logger on first use; here, before the stage threads log through it.
  spdlog::default_logger_raw();
  auto s = std::make_unique<Stages>();
  s->corrections.RecordHistory(!live);  // recorded input: corrections at fixed points
  PoseCorrections* corrections = options_.loop_closure ? &s->corrections : nullptr;
  if (options_.fusion) {
    FusionStageOptions fusion_options = options_.fusion_options;
    fusion_options.drop_when_busy = live;
    fusion_options.predict = options_.frame_to_model;
    std::vector<FusionStage::Variant> variants{
        {options_.fill ? "with_fill" : "without_fill", options_.fill, sink}};
    if (without_fill) variants.push_back({"without_fill", false, without_fill});
    s->fusion =
        std::make_unique<FusionStage>(source.camera(), fusion_options, variants, corrections);
  }
  if (options_.fill) {
    FillStageOptions fill_options = options_.fill_options;
    fill_options.drop_when_busy = live;
    s->fill = std::make_unique<FillStage>(source.camera(), fill_options, sink, s->fusion.get());
  }
  if (options_.loop_closure) {
    LoopStageOptions loop_options = options_.loop_options;
    loop_options.drop_when_busy = live;
    loop_options.same_place = options_.tracker.keyframes;
    // On the images tracking works on: undistorted (FrameToKeyframeTracker).
    Camera pinhole = source.camera();
    pinhole.distortion = {};
    s->loop = std::make_unique<LoopClosureStage>(pinhole, loop_options, &s->corrections);
  }
  s->queue = std::make_unique<BoundedQueue<FrameItem>>(options_.queue_capacity);
  s->reader = std::make_unique<ReadStage>(&source, options_.first_frame, options_.end_frame,
                                          s->queue.get());
  s->tracker = std::make_unique<TrackStage>(
      source, options_.tracker,
      options_.camera_file.empty() ? source.Input() : options_.camera_file, s->queue.get(),
      s->fill.get(), s->fusion.get(), s->loop.get(), options_.frame_to_model);
  return s;
}

ReconstructionSummary Reconstruction::Summarise(const FrameSource& source, const Stages& s,
                                                const std::exception_ptr& error,
                                                const std::string& stop_reason,
                                                double seconds) const {
  const TrackingRecord& tracking = s.tracker->record();
  ReconstructionSummary summary;
  summary.complete = !error && stop_reason.empty();
  summary.stopped_because = error ? Describe(error) : stop_reason;
  summary.frames = tracking.frames;
  summary.lost = tracking.lost;
  summary.keyframes = tracking.keyframes;
  summary.seconds = seconds;
  summary.fps = summary.seconds > 0 ? summary.frames / summary.seconds : 0;
  if (s.fill) {
    const FillReport f = s.fill->Report();
    summary.hole_pixels = f.hole_pixels;
    summary.filled_pixels = f.filled_pixels;
    for (const FailedKeyframe& k : f.failed_keyframes)
      summary.warnings.push_back("keyframe " + k.timestamp + " not filled: " + k.reason);
  }
  if (s.fusion) summary.surfels = s.fusion->Report().count;
  if (s.loop) summary.loops = s.loop->Report().accepted;
  summary.most_lost = summary.frames >= 2 && summary.lost > kMostFramesLost * summary.frames;
  if (summary.most_lost)
    summary.warnings.push_back("tracking was lost on " + std::to_string(summary.lost) + " of " +
                               std::to_string(summary.frames) + " frames");
  if (summary.complete) RefuseIfUnusable(s, &summary);
  summary.report =
      MakeReport(options_, source, tracking, s.fill.get(), s.fusion.get(), s.loop.get(), summary);
  return summary;
}

void Reconstruction::RefuseIfUnusable(const Stages& s, ReconstructionSummary* summary) const {
  std::string why;
  const int tracked = summary->frames - summary->lost;
  if (summary->most_lost && !options_.allow_lost) {
    why = summary->warnings.back() +
          ": the trajectory is not usable (is the depth valid? `glassfusion info` shows its "
          "holes; --allow-lost accepts such a run)";
  } else if (s.fusion && tracked > 0) {
    const SurfelReport f = s.fusion->Report();
    if (f.failed_frames >= tracked)
      why = "the fusion failed on every frame (" + std::to_string(tracked) +
            "): " + f.first_failure.value_or("");
    else if (summary->surfels == 0)
      why = "the map is empty: no surface was seen by enough of the " + std::to_string(tracked) +
            " tracked frames to be kept (too few frames, or are the camera and the depth scale "
            "right?)";
  }
  if (why.empty() && s.fill) {
    const FillReport f = s.fill->Report();
    const size_t failed = f.failed_keyframes.size();
    if (failed > 0 && failed == static_cast<size_t>(f.keyframes_filled))
      why = "the fill failed on every keyframe (" + std::to_string(failed) +
            "): " + f.failed_keyframes[0].reason;
  }
  if (why.empty()) return;
  summary->complete = false;
  summary->refused = true;
  summary->stopped_because = why;
  summary->stopped_during = "checking the result";
}

namespace {

// `report` as written while the run has not finished: "complete" false, and why.
RunReport Unfinished(RunReport report, const std::string& phase) {
  report.complete = false;
  report.stopped_because =
      "unfinished: the run had not finished when this report was written (it is still running, "
      "or it was killed)";
  report.stopped_during = phase;
  return report;
}

// The summary and its report marked not complete, `because`, during `phase`.
void MarkIncomplete(const std::string& because, const std::string& phase,
                    ReconstructionSummary* summary) {
  summary->complete = false;
  summary->stopped_because = because;
  summary->stopped_during = phase;
  summary->report.complete = false;
  summary->report.stopped_because = because;
  summary->report.stopped_during = phase;
}

// The report of the without-fill folder (compare): the same run, its own map, no fill.
RunReport WithoutFillReport(RunReport report, const SurfelReport& surfels) {
  report.config.stereo_fill = false;
  report.fill.reset();
  report.surfels = surfels;
  return report;
}

}  // namespace

void Reconstruction::WriteOutputs(const Stages& s, RunSink* sink, RunSink* without_fill,
                                  const ReconstructionSummary& summary) const {
  const Trajectory trajectory = CorrectedTrajectory(s.tracker->record(), s.corrections);
  const std::string next = "map completion";
  sink->WriteTrajectory(trajectory);
  sink->WriteReport(summary.complete ? Unfinished(summary.report, next) : summary.report);
  if (!without_fill) return;
  without_fill->WriteTrajectory(trajectory);
  without_fill->WriteReport(summary.complete ? Unfinished(summary.report_without_fill, next)
                                             : summary.report_without_fill);
}

void Reconstruction::CompleteKeyframes(const Stages& s, RunSink* sink,
                                       const std::function<bool()>& stop,
                                       const std::string& stop_reason,
                                       ReconstructionSummary* summary) const {
  if (!s.fill || !s.fusion || !options_.fusion_options.complete_keyframes) return;
  std::vector<std::string> warnings;
  const ModelCompletionReport record =
      CompleteFromMap(*s.fill, s.fusion.get(), CorrectedTrajectory(s.tracker->record(), s.corrections),
                      s.tracker->record().names, sink, stop, &warnings);
  summary->report.fill->model_completion = record;
  for (const std::string& w : warnings) {
    summary->warnings.push_back(w);
    summary->report.warnings.push_back(w);
  }
  if (record.stopped)
    MarkIncomplete(stop_reason,
                   "map completion (" + std::to_string(record.keyframes_done) + " of " +
                       std::to_string(record.keyframes_to_do) + " keyframes done)",
                   summary);
}

namespace {

// The frames a run over `source` will read (none: a live input, of no known length).
std::optional<int> FramesToRun(FrameSource& source, int first_frame, int end_frame) {
  std::optional<int> total = source.FrameCount();
  if (!total) return total;
  const int last = end_frame >= 0 ? std::min(*total, end_frame) : *total;
  return std::max(0, last - first_frame);
}

// The camera of the run's images, written first (frames arrive registered to colour; keyframe
// depth PNGs are millimetres): the sink needs it for the keyframes it writes, a partial run has
// it too.
void WriteRunCamera(FrameSource& source, RunSink* sink, RunSink* without_fill) {
  CameraFile run_camera;
  run_camera.camera = source.camera();
  run_camera.depth_scale = 1000.0;
  sink->WriteCamera(run_camera);
  if (without_fill) without_fill->WriteCamera(run_camera);
}

}  // namespace

CpuSecondsReport Reconstruction::CpuReportOf(const Stages& s, double process_cpu_s,
                                             double seconds) {
  CpuSecondsReport c;
  c.stages = {{"read", s.reader->cpu_seconds()},
              {"track", s.tracker->cpu_seconds()},
              {"fill", s.fill ? s.fill->cpu_seconds() : 0.0},
              {"fusion", s.fusion ? s.fusion->cpu_seconds() : 0.0},
              {"loop_closure", s.loop ? s.loop->cpu_seconds() : 0.0}};
  double own = 0;
  for (const auto& [name, cpu] : c.stages) own += cpu;
  c.other = std::max(0.0, process_cpu_s - own);
  c.process = process_cpu_s;
  c.cores_used = seconds > 0 ? process_cpu_s / seconds : 0.0;
  c.cores = std::thread::hardware_concurrency();
  return c;
}

ReconstructionSummary Reconstruction::Run(FrameSource& source, RunSink* sink,
                                          const ReconstructionCallbacks& callbacks,
                                          RunSink* without_fill) {
  GF_CHECK(!without_fill || (options_.fill && options_.fusion),
           "a run without fill beside this one needs the fill and the fusion");
  const auto start = Clock::now();
  const double cpu_start = ProcessCpuSeconds();
  ReconstructionProgress progress;
  progress.total = FramesToRun(source, options_.first_frame, options_.end_frame);
  const bool live = !progress.total.has_value();  // live input: tracking never waits
  WriteRunCamera(source, sink, without_fill);
  std::unique_ptr<Stages> s = MakeStages(source, sink, without_fill, live);
  std::string stop_reason, phase = "tracking", stop_phase, error_phase;
  // Progress and stop requests, from this thread; true once a stop was asked for.
  auto poll = [&] {
    progress.frames = s->tracker->frames();
    if (s->fill)
      progress.keyframes_offered = s->fill->offered(), progress.keyframes_filled = s->fill->done();
    if (s->loop) progress.keyframes_searched = s->loop->keyframes_done();
    if (s->fusion) progress.frames_fused = s->fusion->frames_fused();
    if (callbacks.progress) callbacks.progress(progress);
    if (stop_reason.empty() && callbacks.stop && !(stop_reason = callbacks.stop()).empty())
      stop_phase = phase;
    return !stop_reason.empty();
  };
  while (!s->tracker->WaitFor(std::chrono::milliseconds(50)))
    if (poll()) {
      s->tracker->Stop();
      s->reader->Stop();
    }
  s->reader->Stop();
  s->tracker->Join();
  s->reader->Join();
  progress.tracking_done = true;
  std::exception_ptr error = s->tracker->error();
  if (error) error_phase = phase;
  // The keyframes tracked before an error are valid: the fill, loop closure and fusion finish
  // them, unless a stop is asked for; the fusion last, with the fills and the final corrections.
  auto finish = [&](const char* name, const std::function<void()>& f) {
    phase = name;
    const bool had_error = error != nullptr;
    FinishStage(f, &error);
    if (!had_error && error) error_phase = name;
  };
  if (s->fill) finish("fill", [&] { s->fill->Finish(poll); });
  if (s->loop) finish("loop closure", [&] { s->loop->Finish(poll); });
  if (s->fusion)
    finish("fusion", [&] {
      // Colour views of the run for the clear objects' outlines (none without the fill's
      // keyframes), at the final corrections: loop closure has finished.
      OutlineViews views;
      if (s->fill)
        views = KeyframeViews(*s->fill, CorrectedTrajectory(s->tracker->record(), s->corrections),
                              s->tracker->record().names, *sink,
                              options_.fusion_options.fusion.glass.revolution.outline_views);
      s->fusion->Finish(poll, views);
    });
  if (!error && stop_reason.empty() && s->tracker->record().frames == 0)
    error = std::make_exception_ptr(InputError(source.Input(), "no frames in the selected range"));
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  ReconstructionSummary summary = Summarise(source, *s, error, stop_reason, seconds);
  summary.report.stages.cpu_seconds = CpuReportOf(*s, ProcessCpuSeconds() - cpu_start, seconds);
  summary.report.stages.peak_resident_mib = PeakResidentMiB();
  if (!summary.complete && summary.stopped_during.empty())
    summary.stopped_during = error ? error_phase : stop_phase;
  if (!summary.complete) summary.report.stopped_during = summary.stopped_during;
  if (without_fill) {
    const SurfelReport without = s->fusion->Report(1);
    summary.surfels_without_fill = without.count;
    summary.report_without_fill = WithoutFillReport(summary.report, without);
  }
  WriteOutputs(*s, sink, without_fill, summary);
  phase = "map completion";
  if (summary.complete) CompleteKeyframes(*s, sink, poll, stop_reason, &summary);
  // The whole run, the map's completion of the keyframes included.
  summary.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  summary.fps = summary.seconds > 0 ? summary.frames / summary.seconds : 0;
  summary.report.seconds = summary.seconds;
  summary.report.fps = summary.fps;
  WriteFinalReports(callbacks, sink, without_fill, &summary);
  poll();
  if (error) std::rethrow_exception(error);
  return summary;
}

void Reconstruction::WriteFinalReports(const ReconstructionCallbacks& callbacks, RunSink* sink,
                                       RunSink* without_fill,
                                       ReconstructionSummary* summary) const {
  if (summary->complete && callbacks.finish) {
    try {
      callbacks.finish(summary->report);
    } catch (const std::exception& e) {
      summary->warnings.push_back(e.what());
      summary->report.warnings.push_back(e.what());
      spdlog::warn("{}", e.what());
    }
  }
  if (without_fill) {
    // The same end as the run's: complete, or stopped and why.
    summary->report_without_fill.complete = summary->report.complete;
    summary->report_without_fill.stopped_because = summary->report.stopped_because;
    summary->report_without_fill.stopped_during = summary->report.stopped_during;
    without_fill->WriteReport(summary->report_without_fill);
  }
  sink->WriteReport(summary->report);
}

}  // namespace gf
