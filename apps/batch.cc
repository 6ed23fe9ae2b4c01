#include "apps/batch.h"

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
#include <map>
#include <sstream>
#include <thread>

#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/json_text.h"
#include "apps/interrupt.h"
#include "apps/progress.h"

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

// A folder name per capture, unique within the batch.
std::string UniqueName(const std::string& input, std::map<std::string, int>* used) {
  std::string name = fs::path(input).filename().string();
  if (name.empty() || name == "." || name == "..") name = "capture";
  const int n = ++(*used)[name];
  return n == 1 ? name : name + "_" + std::to_string(n);
}

// Whether DIR/<name> holds a complete comparison made with the same settings.
bool AlreadyDone(const std::string& out_dir, const BatchCapture& c) {
  const fs::path run = fs::path(out_dir) / c.name;
  const json state = ReadJsonIfAny((StateDir(out_dir) / (c.name + ".json")).string());
  const json report = ReadJsonIfAny((run / "with_fill" / "report.json").string());
  return IsRegularFile((run / "compare.json").string()) && state.is_object() &&
         state.value("status", "") == "done" &&
         state.value("fingerprint", "") == SettingsFingerprint(c) && report.is_object() &&
         report.value("complete", false);
}

// Starts `glassfusion compare` for a capture, its output appended to `log`. Returns the pid.
pid_t Launch(const std::string& self, const BatchCapture& c, const std::string& out_dir,
             const std::string& log) {
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
  pid_t pid = 0;
  int attempt = 1;
  Clock::time_point start;
};

// Runs `todo` with at most `jobs` children at once; calls `finished(capture, ok, attempts,
// seconds)` for each. A failed attempt is retried up to `retries` more times.
void RunChildren(const BatchOptions& options, const std::vector<BatchCapture>& todo,
                 const std::function<void(const Running&, bool, double)>& finished) {
  const std::string self = ExecutablePath();
  std::vector<Running> running;
  std::vector<Running> queue;
  for (const BatchCapture& c : todo) queue.push_back({c, 0, 1, {}});
  std::reverse(queue.begin(), queue.end());  // pop_back takes them in manifest order
  auto stopping = [&] { return options.interrupt && options.interrupt->load() != 0; };
  bool forwarded = false;
  while (!queue.empty() || !running.empty()) {
    while (!stopping() && !queue.empty() && static_cast<int>(running.size()) < options.jobs) {
      Running r = queue.back();
      queue.pop_back();
      r.start = Clock::now();
      r.pid = Launch(self, r.capture, options.out_dir,
                     (StateDir(options.out_dir) / (r.capture.name + ".log")).string());
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
        queue.push_back({r.capture, 0, r.attempt + 1, {}});
      } else {
        finished(r, ok, seconds);
      }
      break;
    }
  }
}

void WriteState(const std::string& out_dir, const Running& r, bool ok, double seconds) {
  const std::string log = (StateDir(out_dir) / (r.capture.name + ".log")).string();
  const json state = {{"name", r.capture.name},
                      {"input", r.capture.input},
                      {"config", r.capture.config_file},
                      {"status", ok ? "done" : "failed"},
                      {"attempts", r.attempt},
                      {"seconds", seconds},
                      {"fingerprint", SettingsFingerprint(r.capture)},
                      {"error", ok ? json() : json(LastError(log))},
                      {"log", fs::path(log).filename().string()}};
  WriteTextFileAtomically((StateDir(out_dir) / (r.capture.name + ".json")).string(),
                          JsonText(state) + "\n");
}

}  // namespace

bool BatchOptions::Check(std::string* message) const {
  std::string problem;
  if (manifest.empty() || out_dir.empty()) problem = "need MANIFEST and --out";
  if (jobs < 1) problem = "--jobs must be at least 1";
  if (retries < 0) problem = "retries must be 0 or more";
  if (slurm_cpus_per_task < 1 || slurm_max_running < 0) problem = "bad Slurm resources";
  if (submit && !slurm) problem = "--submit needs --slurm";
  if (message) *message = problem;
  return problem.empty();
}

std::vector<BatchCapture> ReadManifest(const std::string& manifest,
                                       const std::string& default_config) {
  std::vector<BatchCapture> captures;
  std::map<std::string, int> used;
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

void WriteBatchManifest(const std::string& out_dir, const std::vector<BatchCapture>& captures) {
  json list = json::array();
  for (const BatchCapture& c : captures)
    list.push_back({{"name", c.name}, {"input", c.input}, {"config", c.config_file}});
  WriteTextFileAtomically((StateDir(out_dir) / "manifest.json").string(),
                          JsonText(json({{"captures", list}})) + "\n");
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

std::string SettingsFingerprint(const BatchCapture& c) {
  std::string text = std::string("glassfusion ") + GF_VERSION + "\n" + c.input + "\n";
  if (!c.config_file.empty())
    text += IsRegularFile(c.config_file) ? ReadTextFile(c.config_file) : "missing " + c.config_file;
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016zx", std::hash<std::string>{}(text));
  return hex;
}

BatchSummary RunBatch(const BatchOptions& options) {
  std::string problem;
  if (!options.Check(&problem)) throw InputError("batch", problem);
  const std::vector<BatchCapture> captures = ReadManifest(options.manifest, options.config_file);
  if (options.task >= static_cast<int>(captures.size()))
    throw InputError(options.manifest, "--task " + std::to_string(options.task) + ": it lists " +
                                           std::to_string(captures.size()) + " captures");
  std::error_code ec;
  fs::create_directories(StateDir(options.out_dir), ec);
  if (ec) throw InputError(options.out_dir, "cannot create output folder: " + ec.message());
  if (options.task < 0) WriteBatchManifest(options.out_dir, captures);
  std::vector<BatchCapture> todo;
  int skipped = 0;
  for (int i = 0; i < static_cast<int>(captures.size()); ++i) {
    if (options.task >= 0 && i != options.task) continue;
    if (AlreadyDone(options.out_dir, captures[i]))
      ++skipped;
    else
      todo.push_back(captures[i]);
  }
  TerminalProgress progress("batch", static_cast<int>(todo.size()));
  int finished = 0;
  RunChildren(options, todo, [&](const Running& r, bool ok, double seconds) {
    WriteState(options.out_dir, r, ok, seconds);
    progress.Update(++finished, r.capture.name + (ok ? " done" : " failed"));
  });
  progress.Finish();
  if (options.task >= 0) {  // one Slurm task: the summary is --collect's
    BatchSummary s;
    s.captures = 1, s.skipped = skipped, s.done = finished;
    return s;
  }
  BatchSummary s = CollectBatch(options.out_dir);
  s.skipped = skipped;
  if (options.interrupt && *options.interrupt)
    throw Interrupted(*options.interrupt,
                      options.out_dir + ": batch stopped by " + SignalName(*options.interrupt) +
                          " after " + std::to_string(finished) + " captures; summary written");
  return s;
}

}  // namespace gf
