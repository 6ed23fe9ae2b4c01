// `glassfusion batch MANIFEST --out DIR`: reprocess many captures, each as `compare` does (tracked
// once, fused with and without the fill), and summarise what each gained.
//
// MANIFEST is a text file with one capture per line, `PATH [--config FILE]` (relative paths from
// the manifest's folder; blank lines and lines starting with '#' are skipped), or a folder whose
// sub-folders are the captures (sorted by name). Capture i runs in DIR/<name>/ as a child process
// `glassfusion compare PATH --out DIR/<name> --force [--config FILE]`, so that one capture's crash
// cannot take the others down; its log goes to DIR/batch/<name>.log and its state to
// DIR/batch/<name>.json ({"status": "done" | "failed", "attempts", "seconds", "fingerprint",
// "error"}). A failed capture is retried once, then reported; the others go on.
//
// Names: <name> is the capture's folder (or file) name, made unique in manifest order: the first
// capture takes its name, a later one whose name is taken (or is one of the batch's own: batch,
// summary.csv, summary.html, batch.sbatch) gets the first free <name>_2, <name>_3, ... So x/cap,
// y/cap, z/cap_2 become cap, cap_2, cap_2_2: no two captures ever share a folder. The names follow
// the manifest's order; reordering it may rename captures (they are then rerun, see Resume).
//
// Resume: a capture whose DIR/<name>/compare.json exists, whose run says "complete": true and
// whose state's fingerprint matches is skipped. The fingerprint (taken before the capture runs)
// covers glassfusion's version, the input's path, the settings file's contents and the capture's
// contents: every file under a capture folder by relative path, size and modification time (the
// .txt and .json files, e.g. rgb.txt, depth.txt, INDEX.txt, camera.json, by content too), or a
// capture file's (.oni) size and modification time. Editing a frame makes the capture run again.
//
// Safety: DIR is a RunFolder (acquisition/run_folder.h) that batch only adds to (its marker lists
// the state files and summaries it writes); it must not be, contain or lie inside a capture (or
// the manifest's folder of captures), and a second batch into DIR is refused while one runs (the
// tasks of one Slurm job array share it). Each child `compare --force` replaces only what its own
// earlier run in DIR/<name> listed; it refuses a DIR/<name> that is not a run folder.
//
// Slurm (--slurm): writes DIR/batch.sbatch, a job array with one capture per task (each task runs
// `glassfusion batch MANIFEST --out DIR --task $SLURM_ARRAY_TASK_ID`), and submits it with sbatch
// when --submit is given; `glassfusion batch --collect DIR` then builds the summary from whatever
// tasks have finished. Every node must see MANIFEST's captures, DIR and the glassfusion executable
// at the same paths (a shared filesystem).
//
// Summary: DIR/summary.csv and DIR/summary.html (report writer of report/report_html.h): per capture
// its status, frames, time, ATE where ground truth exists, surfels with and without the fill,
// completeness gain where ground truth exists, fill rate, a link to its report; totals first.
#pragma once

#include <atomic>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/run_folder.h"
#include "acquisition/run_layout.h"
#include "pipeline/run_report.h"

namespace gf {

struct BatchCapture {
  std::string name;         // its folder under DIR
  std::string input;        // absolute path
  std::string config_file;  // absolute path, or empty
};

struct BatchOptions {
  std::string manifest;                 // a manifest file or a folder of captures
  std::string out_dir;                  // DIR
  std::string config_file;              // settings for captures whose manifest line names none
  int jobs = 1;                         // captures processed at once on this machine
  int retries = 1;                      // further attempts after a failed one
  int task = -1;                        // >= 0: process capture `task` only (a Slurm array task)
  bool slurm = false;                   // write DIR/batch.sbatch instead of processing
  bool submit = false;                  // with slurm: submit it with sbatch
  int slurm_max_running = 0;            // the array's %K: tasks running at once (0 = no limit)
  int slurm_cpus_per_task = 2;          // cores per task (the stages use 2)
  std::string slurm_memory = "4G";      // memory per task (--mem)
  std::string slurm_time = "02:00:00";  // time limit per task (--time)
  const std::atomic<int>* interrupt = nullptr;  // Ctrl-C: stop launching, finish, summarise
  bool Check(std::string* message = nullptr) const;
};

// The captures MANIFEST lists, in order; `default_config` for those without their own. Throws
// InputError naming the manifest line that is wrong.
std::vector<BatchCapture> ReadManifest(const std::string& manifest,
                                       const std::string& default_config);

// What decides whether an earlier run can be kept: the version, the input's path and contents,
// the settings' text (see Resume above). 16 hex digits.
std::string SettingsFingerprint(const BatchCapture& capture);

struct BatchSummary {
  int captures = 0, done = 0, skipped = 0, failed = 0, pending = 0;
  std::string BriefReport() const;
};

// Processes the captures (all, or options.task), then writes the summary. Throws Interrupted
// when stopped by a signal (after the summary of what finished).
BatchSummary RunBatch(const BatchOptions& options);

// DIR/batch.sbatch for the manifest's captures; submits it when options.submit. Returns its path.
std::string WriteSlurmScript(const BatchOptions& options);

// DIR/summary.csv and DIR/summary.html from the state of every capture of DIR/batch/manifest.json
// (takes DIR's lock shared, as the tasks of a job array do).
BatchSummary CollectBatch(const std::string& out_dir);
// The same into a batch folder the caller holds.
BatchSummary WriteBatchSummary(RunFolder* out);

// `sbatch --parsable SCRIPT`: returns the job id. Throws InputError when sbatch fails or is absent.
std::string SubmitSlurmScript(const std::string& script);

// Shared by the two halves: DIR/batch/manifest.json (the captures, in order), and a JSON file read
// back (null when absent or unreadable, e.g. half-written by a task killed mid-write elsewhere).
void WriteBatchManifest(RunFolder* out, const std::vector<BatchCapture>& captures);
// DIR opened as a batch folder (see Safety above) for `captures` read from `manifest`; `shared`
// for one task of a job array or --collect.
std::unique_ptr<RunFolder> OpenBatchFolder(const std::string& out_dir, const std::string& manifest,
                                           const std::vector<BatchCapture>& captures, bool shared);
// This executable (/proc/self/exe): child captures and Slurm tasks run the same build.
std::string ExecutablePath();
nlohmann::ordered_json ReadJsonIfAny(const std::string& path);
// A run folder's report.json, or none when it is missing or not a run's report.
std::optional<RunReport> ReportIfAny(const RunLayout& run);

}  // namespace gf
