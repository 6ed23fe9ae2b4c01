// The CPU time a run used, by stage, and the process's resident memory (Linux: /proc/self/statm
// and getrusage). How long a stage's steps took is StepTimes (pipeline/stage_reports.h).
#pragma once

#include <sys/resource.h>

#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>
#include <utility>
#include <vector>

namespace gf {

// CPU seconds (user and system) the whole process has used so far, every thread.
inline double ProcessCpuSeconds() {
  rusage use{};
  getrusage(RUSAGE_SELF, &use);
  auto secs = [](const timeval& t) { return t.tv_sec + 1e-6 * t.tv_usec; };
  return secs(use.ru_utime) + secs(use.ru_stime);
}

// report.json's stages.cpu_seconds: each stage thread's own CPU time, `other` the rest of the
// process (OpenCV's worker pool, which runs the stages' parallel loops, and the calling thread),
// `process` all of it, and `cores_used` = process / wall seconds, beside the machine's cores.
inline nlohmann::ordered_json CpuReport(const std::vector<std::pair<const char*, double>>& stages, double process,
               double wall) {
  nlohmann::ordered_json out;
  double own = 0;
  for (const auto& [name, cpu] : stages) {
    out[name] = cpu;
    own += cpu;
  }
  out["other"] = std::max(0.0, process - own);
  out["process"] = process;
  out["cores_used"] = wall > 0 ? process / wall : 0.0;
  out["cores"] = std::thread::hardware_concurrency();
  return out;
}

// Resident memory of the process now, MiB (0 where /proc is not there).
inline double ResidentMiB() {
  std::ifstream statm("/proc/self/statm");
  long pages_total = 0, pages_resident = 0;
  if (!(statm >> pages_total >> pages_resident)) return 0;
  return static_cast<double>(pages_resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) /
         (1024.0 * 1024.0);
}

// The most resident memory the process has held since it started, MiB.
inline double PeakResidentMiB() {
  rusage use{};
  getrusage(RUSAGE_SELF, &use);
  return static_cast<double>(use.ru_maxrss) / 1024.0;  // ru_maxrss: KiB on Linux
}

}  // namespace gf
