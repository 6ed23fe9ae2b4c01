#include "pipeline/run_report.h"

#include "pipeline/json_fields.h"

namespace gf {
namespace {

using json = nlohmann::ordered_json;
using json_fields::Object;
using json_fields::OrNull;
using json_fields::Read;

}  // namespace

const StepTimes* StagesReport::Find(const std::string& stage) const {
  for (const auto& [name, times] : steps)
    if (name == stage) return &times;
  return nullptr;
}

void to_json(json& j, const RunConfigReport& c) {
  j = {{"tracker", c.tracker},
       {"stereo_fill", c.stereo_fill},
       {"surfel_fusion", c.surfel_fusion},
       {"loop_closure", c.loop_closure},
       {"threads", c.threads},
       {"hardware_concurrency", c.hardware_concurrency},
       {"file", OrNull(c.file)},
       {"settings", c.settings}};
}

void from_json(const json& j, RunConfigReport& c) {
  Read(j, "tracker", &c.tracker);
  Read(j, "stereo_fill", &c.stereo_fill);
  Read(j, "surfel_fusion", &c.surfel_fusion);
  Read(j, "loop_closure", &c.loop_closure);
  Read(j, "threads", &c.threads);
  Read(j, "hardware_concurrency", &c.hardware_concurrency);
  Read(j, "file", &c.file);
  Read(j, "settings", &c.settings);
}

void to_json(json& j, const CpuSecondsReport& c) {
  j = Object(c.stages);
  j["other"] = c.other;
  j["process"] = c.process;
  j["cores_used"] = c.cores_used;
  j["cores"] = c.cores;
}

void from_json(const json& j, CpuSecondsReport& c) {
  c.stages.clear();
  for (const auto& [name, value] : j.items()) {
    if (name == "other" || name == "process" || name == "cores_used" || name == "cores") continue;
    c.stages.push_back({name, value.get<double>()});
  }
  Read(j, "other", &c.other);
  Read(j, "process", &c.process);
  Read(j, "cores_used", &c.cores_used);
  Read(j, "cores", &c.cores);
}

void to_json(json& j, const RunReport& r) {
  j = {{"complete", r.complete}};
  if (!r.complete) {
    j["stopped_because"] = r.stopped_because;
    j["stopped_during"] = r.stopped_during;
  }
  j["input"] = {{"path", r.input.path},
                {"kind", r.input.kind},
                {"first_frame", r.input.first_frame},
                {"end_frame", r.input.end_frame}};
  j["config"] = r.config;
  j["frames"] = r.frames;
  j["fps"] = r.fps;
  j["seconds"] = r.seconds;
  json& stages = j["stages"] = Object(r.stages.steps);
  if (r.stages.cpu_seconds) stages["cpu_seconds"] = *r.stages.cpu_seconds;
  if (r.stages.peak_resident_mib) stages["peak_resident_mib"] = *r.stages.peak_resident_mib;
  j["keyframes"] = r.keyframes;
  j["tracking"] = {{"lost_frames", r.tracking.lost_frames},
                   {"relocalised", r.tracking.relocalised},
                   {"restarted", r.tracking.restarted},
                   {"lost", r.tracking.lost}};
  j["loops"] = r.loops;
  j["fill"] = OrNull(r.fill);
  j["surfels"] = OrNull(r.surfels);
  j["warnings"] = r.warnings;
}

void from_json(const json& j, RunReport& r) {
  Read(j, "complete", &r.complete);
  Read(j, "stopped_because", &r.stopped_because);
  Read(j, "stopped_during", &r.stopped_during);
  if (j.contains("input")) {
    const json& in = j["input"];
    Read(in, "path", &r.input.path);
    Read(in, "kind", &r.input.kind);
    Read(in, "first_frame", &r.input.first_frame);
    Read(in, "end_frame", &r.input.end_frame);
  }
  Read(j, "config", &r.config);
  Read(j, "frames", &r.frames);
  Read(j, "fps", &r.fps);
  Read(j, "seconds", &r.seconds);
  r.stages = {};
  if (j.contains("stages") && j["stages"].is_object())
    for (const auto& [name, value] : j["stages"].items()) {
      if (name == "cpu_seconds")
        r.stages.cpu_seconds = value.get<CpuSecondsReport>();
      else if (name == "peak_resident_mib")
        r.stages.peak_resident_mib = value.get<double>();
      else
        r.stages.steps.push_back({name, value.get<StepTimes>()});
    }
  Read(j, "keyframes", &r.keyframes);
  if (j.contains("tracking")) {
    const json& t = j["tracking"];
    Read(t, "lost_frames", &r.tracking.lost_frames);
    Read(t, "relocalised", &r.tracking.relocalised);
    Read(t, "restarted", &r.tracking.restarted);
    Read(t, "lost", &r.tracking.lost);
  }
  Read(j, "loops", &r.loops);
  Read(j, "fill", &r.fill);
  Read(j, "surfels", &r.surfels);
  Read(j, "warnings", &r.warnings);
}

}  // namespace gf
