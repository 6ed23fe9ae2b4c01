#include "batch/batch.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <thread>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/json_text.h"
#include "acquisition/progress.h"
#include "acquisition/run_layout.h"
#include "pipeline/run_reader.h"

extern char** environ;

namespace fs = std::filesystem;

namespace gf {
namespace {

using json = nlohmann::ordered_json;
using Clock = std::chrono::steady_clock;

fs::path StateDir(const std::string& out_dir) { return fs::path(out_dir) / "batch"; }

std::string Absolute(const fs::path& path, const fs::path& base) {
  return fs::weakly_canonical(path.is_absolute() ? path : base / path).string();
}

// A folder name per capture, unique within the batch (batch.h, Names).
std::string UniqueName(const std::string& input, std::set<std::string>* taken) {
  fs::path path(input);
  if (path.filename().empty()) path = path.parent_path();  // "cap/"
  std::string base = path.filename().string();
  if (base.empty() || base == "." || base == "..") base = "capture";
  static const std::set<std::string> kOurs = {
      "batch",        "summary.csv",          "summary.html",
      "batch.sbatch", RunFolder::kMarkerName, RunFolder::kLockName};
  std::string name = base;
  for (int n = 2; taken->count(name) || kOurs.count(name); ++n)
    name = base + "_" + std::to_string(n);
  taken->insert(name);
  return name;
}

// Whether DIR/<name> holds a complete comparison made with the same settings and input.
bool AlreadyDone(const std::string& out_dir, const BatchCapture& c,
                 const std::string& fingerprint) {
  const RunLayout run((fs::path(out_dir) / c.name).string());
  const json state = ReadJsonIfAny((StateDir(out_dir) / (c.name + ".json")).string());
  return IsRegularFile(run.Path(RunLayout::kCompare)) && state.is_object() &&
         state.value("status", "") == "done" && state.value("fingerprint", "") == fingerprint &&
         ReportIfAny(run.Map(true)).value_or(RunReport()).complete;
}

// 64-bit FNV-1a: the same digits on every build and machine (std::hash promises neither).
struct Fnv {
  uint64_t hash = 1469598103934665603ull;
  void Add(const std::string& text) {
    for (unsigned char c : text) hash = (hash ^ c) * 1099511628211ull;
    hash = (hash ^ 0xff) * 1099511628211ull;  // a separator: "ab","c" differs from "a","bc"
  }
};

// A file's size and modification time (nanoseconds), as text.
std::string SizeAndTime(const fs::path& file) {
  std::error_code ec;
  const auto size = fs::file_size(file, ec);
  const auto time = fs::last_write_time(file, ec).time_since_epoch().count();
  return ec ? "unreadable" : std::to_string(size) + " " + std::to_string(time);
}

// The capture's contents into `fnv`: a file's size and time; a folder's files by relative path
// (sorted), with size and time, and the text of its .txt and .json files up to 1 MB (the index
// files: rgb.txt, depth.txt, INDEX.txt, camera.json, ...).
void AddContents(const std::string& input, Fnv* fnv) {
  std::error_code ec;
  if (fs::is_regular_file(input, ec)) return fnv->Add("file " + SizeAndTime(input));
  if (!fs::is_directory(input, ec)) return fnv->Add("missing");
  std::vector<fs::path> files;
  for (auto it = fs::recursive_directory_iterator(
           input, fs::directory_options::skip_permission_denied, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec))
    if (it->is_regular_file(ec)) files.push_back(it->path());
  if (ec) fnv->Add("unlistable " + ec.message());
  std::sort(files.begin(), files.end());
  for (const fs::path& f : files) {
    fnv->Add(f.lexically_relative(input).generic_string() + " " + SizeAndTime(f));
    const std::string ext = f.extension().string();
    if (ext != ".txt" && ext != ".json") continue;
    if (fs::file_size(f, ec) > (1u << 20) || ec) continue;
    try {
      fnv->Add(ReadTextFile(f.string()));
    } catch (const InputError&) {
      fnv->Add("unreadable");
    }
  }
}

// Starts `glassfusion compare` for a capture, its output appended to `log`. Returns the pid.
pid_t Launch(const std::string& self, const BatchCapture& c, const std::string& out_dir,
             const std::string& log) {
  // The child replaces (--force) only what its own earlier run in DIR/<name> listed.
  std::vector<std::string> args = {
      self, "compare", c.input, "--out", (fs::path(out_dir) / c.name).string(), "--force"};
  if (!c.config_file.empty()) args.insert(args.end(), {"--config", c.config_file});
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = 0;
  const int error = posix_spawn(&pid, self.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error) throw InputError(self, std::string("cannot start a capture: ") + strerror(error));
  return pid;
}

// The last "error: ..." line of a capture's log (what went wrong, in the command's own words).
std::string LastError(const std::string& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line))
    if (line.rfind("error: ", 0) == 0 || line.rfind("internal error: ", 0) == 0) last = line;
  return last;
}

struct Running {
  BatchCapture capture;
  std::string fingerprint;  // taken before the first attempt
  pid_t pid = 0;
  int attempt = 1;
  Clock::time_point start;
};

// Runs `todo` with at most `jobs` children at once; calls `finished(capture, ok, attempts,
// seconds)` for each. A failed attempt is retried up to `retries` more times.
void RunChildren(const BatchOptions& options, RunFolder* out, const std::vector<Running>& todo,
                 const std::function<void(const Running&, bool, double)>& finished) {
  const std::string self = ExecutablePath();
  std::vector<Running> running;
  std::vector<Running> queue = todo;
  std::reverse(queue.begin(), queue.end());  // pop_back takes them in manifest order
  auto stopping = [&] { return options.interrupt && options.interrupt->load() != 0; };
  bool forwarded = false;
  while (!queue.empty() || !running.empty()) {
    while (!stopping() && !queue.empty() && static_cast<int>(running.size()) < options.jobs) {
      Running r = queue.back();
      queue.pop_back();
      r.start = Clock::now();
      r.pid =
          Launch(self, r.capture, options.out_dir, out->File("batch/" + r.capture.name + ".log"));
      running.push_back(r);
    }
    if (stopping() && !forwarded) {  // stop: no new captures; the running ones stop too
      queue.clear();
      for (const Running& r : running) kill(r.pid, SIGTERM);
      forwarded = true;
    }
    int status = 0;
    const pid_t pid = waitpid(-1, &status, WNOHANG);
    if (pid == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      continue;
    }
    if (pid < 0) {
      if (errno == EINTR) continue;
      break;  // no children left
    }
    for (size_t i = 0; i < running.size(); ++i) {
      if (running[i].pid != pid) continue;
      Running r = running[i];
      running.erase(running.begin() + i);
      const bool ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
      const double seconds = std::chrono::duration<double>(Clock::now() - r.start).count();
      if (!ok && r.attempt <= options.retries && !stopping()) {
        r.attempt += 1;
        queue.push_back(r);
      } else {
        finished(r, ok, seconds);
      }
      break;
    }
  }
}

void WriteState(RunFolder* out, const Running& r, bool ok, double seconds) {
  const std::string log = (StateDir(out->dir()) / (r.capture.name + ".log")).string();
  const json state = {{"name", r.capture.name},
                      {"input", r.capture.input},
                      {"config", r.capture.config_file},
                      {"status", ok ? "done" : "failed"},
                      {"attempts", r.attempt},
                      {"seconds", seconds},
                      {"fingerprint", r.fingerprint},
                      {"error", ok ? json() : json(LastError(log))},
                      {"log", fs::path(log).filename().string()}};
  WriteTextFileAtomically(out->File("batch/" + r.capture.name + ".json"), JsonText(state) + "\n");
}

}  // namespace

bool BatchOptions::Check(std::string* message) const {
  // Jobs, retries and Slurm's limits count runs: at most one per frame of a day's capture.
  FieldCheck c(message);
  c.Require(!manifest.empty(), "MANIFEST: the list of captures")
      .Require(!out_dir.empty(), "--out: the folder of the runs")
      .In("--jobs", jobs, 1, kMaxCaptureFrames, kMoreFramesThanACapture)
      .In("retries", retries, 0, kMaxCaptureFrames, kMoreFramesThanACapture)
      .In("--cpus-per-task", slurm_cpus_per_task, 1, kMaxCaptureFrames,
          kMoreFramesThanACapture)
      .In("--max-running", slurm_max_running, 0, kMaxCaptureFrames,
          kMoreFramesThanACapture)
      .Require(!submit || slurm, "--submit needs --slurm");
  return c.ok();
}

std::vector<BatchCapture> ReadManifest(const std::string& manifest,
                                       const std::string& default_config) {
  std::vector<BatchCapture> captures;
  std::set<std::string> used;
  const std::string config = default_config.empty() ? "" : Absolute(default_config, ".");
  if (IsDirectory(manifest)) {
    std::vector<std::string> inputs;
    for (const auto& e : fs::directory_iterator(manifest))
      if (e.is_directory() && e.path().filename() != "batch")
        inputs.push_back(Absolute(e.path(), "."));
    std::sort(inputs.begin(), inputs.end());
    for (const std::string& input : inputs)
      captures.push_back({UniqueName(input, &used), input, config});
  } else {
    if (!IsRegularFile(manifest)) throw InputError(manifest, "no such manifest file or folder");
    const fs::path base = fs::absolute(manifest).parent_path();
    std::istringstream lines(ReadTextFile(manifest));
    std::string line;
    for (int number = 1; std::getline(lines, line); ++number) {
      std::istringstream words(line);
      std::string path, flag, file;
      if (!(words >> path) || path[0] == '#') continue;
      BatchCapture c{"", Absolute(path, base), config};
      if (words >> flag) {
        if (flag != "--config" || !(words >> file) || (words >> flag))
          throw InputError(manifest, "line " + std::to_string(number) +
                                         ": expected PATH [--config FILE], got \"" + line + "\"");
        c.config_file = Absolute(file, base);
      }
      c.name = UniqueName(c.input, &used);
      captures.push_back(c);
    }
  }
  if (captures.empty()) throw InputError(manifest, "lists no captures");
  return captures;
}

void WriteBatchManifest(RunFolder* out, const std::vector<BatchCapture>& captures) {
  json list = json::array();
  for (const BatchCapture& c : captures)
    list.push_back({{"name", c.name}, {"input", c.input}, {"config", c.config_file}});
  WriteTextFileAtomically(out->File("batch/manifest.json"),
                          JsonText(json({{"captures", list}})) + "\n");
}

std::unique_ptr<RunFolder> OpenBatchFolder(const std::string& out_dir, const std::string& manifest,
                                           const std::vector<BatchCapture>& captures, bool shared) {
  RunFolder::Options options;
  options.earlier = RunFolder::kKeep;
  options.shared = shared;
  if (IsDirectory(manifest)) options.inputs.push_back(manifest);  // its sub-folders are captures
  for (const BatchCapture& c : captures) options.inputs.push_back(c.input);
  auto folder = std::make_unique<RunFolder>(out_dir, options);
  folder->Folder("batch");
  return folder;
}

std::string ExecutablePath() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw InputError("/proc/self/exe", "cannot find this executable: " + ec.message());
  return self.string();
}

json ReadJsonIfAny(const std::string& path) {
  if (!IsRegularFile(path)) return json();
  try {
    return json::parse(ReadTextFile(path));
  } catch (const std::exception&) {
    return json();
  }
}

std::optional<RunReport> ReportIfAny(const RunLayout& run) {
  try {
    return RunReader(run).Report();
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

std::string SettingsFingerprint(const BatchCapture& c) {
  Fnv fnv;
  fnv.Add(std::string("glassfusion ") + GF_VERSION);
  fnv.Add(c.input);
  if (!c.config_file.empty())
    fnv.Add(IsRegularFile(c.config_file) ? ReadTextFile(c.config_file)
                                         : "missing " + c.config_file);
  AddContents(c.input, &fnv);
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016llx", static_cast<unsigned long long>(fnv.hash));
  return hex;
}

BatchSummary RunBatch(const BatchOptions& options) {
  std::string problem;
  if (!options.Check(&problem)) throw InputError("batch", problem);
  const std::vector<BatchCapture> captures = ReadManifest(options.manifest, options.config_file);
  if (options.task >= static_cast<int>(captures.size()))
    throw InputError(options.manifest, "--task " + std::to_string(options.task) + ": it lists " +
                                           std::to_string(captures.size()) + " captures");
  // The tasks of one Slurm job array share DIR; a whole batch has it to itself.
  const std::unique_ptr<RunFolder> out =
      OpenBatchFolder(options.out_dir, options.manifest, captures, options.task >= 0);
  if (options.task < 0) WriteBatchManifest(out.get(), captures);
  std::vector<Running> todo;
  int skipped = 0;
  for (int i = 0; i < static_cast<int>(captures.size()); ++i) {
    if (options.task >= 0 && i != options.task) continue;
    const std::string fingerprint = SettingsFingerprint(captures[i]);
    if (AlreadyDone(options.out_dir, captures[i], fingerprint))
      ++skipped;
    else
      todo.push_back({captures[i], fingerprint, 0, 1, {}});
  }
  const std::unique_ptr<Progress> progress = ShowProgress("batch", static_cast<int>(todo.size()));
  int finished = 0;
  RunChildren(options, out.get(), todo, [&](const Running& r, bool ok, double seconds) {
    WriteState(out.get(), r, ok, seconds);
    progress->Update(++finished, r.capture.name + (ok ? " done" : " failed"));
  });
  progress->Finish();
  if (options.task >= 0) {  // one Slurm task: the summary is --collect's
    BatchSummary s;
    s.captures = 1, s.skipped = skipped, s.done = finished;
    return s;
  }
  BatchSummary s = WriteBatchSummary(out.get());
  s.skipped = skipped;
  if (options.interrupt && *options.interrupt)
    throw Interrupted(*options.interrupt,
                      options.out_dir + ": batch stopped by " + SignalName(*options.interrupt) +
                          " after " + std::to_string(finished) + " captures; summary written");
  return s;
}

}  // namespace gf
