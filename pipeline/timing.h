// The CPU time the process has used and its resident memory (Linux: getrusage and
// /proc/self/statm). How long a stage's steps took is StepTimes (pipeline/stage_reports.h).
#pragma once

#include <sys/resource.h>

#include <unistd.h>

#include <fstream>

namespace gf {

// CPU seconds (user and system) the whole process has used so far, every thread.
inline double ProcessCpuSeconds() {
  rusage use{};
  getrusage(RUSAGE_SELF, &use);
  auto secs = [](const timeval& t) { return t.tv_sec + 1e-6 * t.tv_usec; };
  return secs(use.ru_utime) + secs(use.ru_stime);
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
