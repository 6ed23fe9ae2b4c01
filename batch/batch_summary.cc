// The batch's summary (CollectBatch) and its Slurm job array (WriteSlurmScript); see batch.h.
#include <cstdio>
#include <filesystem>

#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/run_layout.h"
#include "acquisition/trajectory.h"
#include "acquisition/trajectory_metrics.h"
#include "batch/batch.h"
#include "report/report_html.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

using json = nlohmann::ordered_json;

// One capture's line of the summary; empty strings where a figure does not apply.
struct Row {
  std::string name, status, frames, seconds, ate_m, surfels_with, surfels_without, gain, fill_rate,
      report, error;
};

std::string Fixed(double value, int digits) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.*f", digits, value);
  return buffer;
}

// ATE from compare.json (synthetic ground truth) or from the ground truth beside the input.
std::string Ate(const json& compare, const std::string& input, const RunLayout& run) {
  if (compare.contains("ate_m") && compare["ate_m"].is_number())
    return Fixed(compare["ate_m"].get<double>(), 4);
  const std::string truth = GroundTruthBeside(input);
  const std::string estimate = run.Map(true).Path(RunLayout::kTrajectory);
  if (truth.empty() || !IsRegularFile(estimate)) return "";
  try {
    const TrajectoryErrorSummary ate =
        EvaluateTrajectory(ReadTrajectory(truth), ReadTumTrajectory(estimate));
    return ate.success ? Fixed(ate.ate_rmse_m, 4) : "";
  } catch (const std::exception&) {
    return "";
  }
}

Row MakeRow(const std::string& out_dir, const json& capture) {
  Row row;
  row.name = capture["name"];
  const RunLayout run((fs::path(out_dir) / row.name).string());
  const json state = ReadJsonIfAny((fs::path(out_dir) / "batch" / (row.name + ".json")).string());
  row.status = state.is_object() ? state.value("status", "pending") : "pending";
  if (state.is_object()) row.seconds = Fixed(state.value("seconds", 0.0), 1);
  if (row.status == "failed") row.error = state["error"].is_string() ? state["error"] : "";
  const json compare = ReadJsonIfAny(run.Path(RunLayout::kCompare));
  const std::optional<RunReport> report = ReportIfAny(run.Map(true));
  if (row.status != "done" || !compare.is_object() || !report) return row;
  row.frames = std::to_string(compare.value("frames", 0));
  row.ate_m = Ate(compare, capture["input"], run);
  row.surfels_with = compare["with_fill"]["surfels"]["count"].dump();
  row.surfels_without = compare["without_fill"]["surfels"]["count"].dump();
  const json& with = compare["with_fill"];
  if (with.contains("completeness") && with["completeness"]["overall"].is_object())
    row.gain =
        Fixed(with["completeness"]["overall"]["within_2cm"].get<double>() -
                  compare["without_fill"]["completeness"]["overall"]["within_2cm"].get<double>(),
              4);
  if (report->fill) row.fill_rate = Fixed(report->fill->fill_rate(), 4);
  row.report = row.name + "/report.html";
  return row;
}

std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

void WriteSummary(RunFolder* out, const std::vector<Row>& rows, const BatchSummary& s) {
  std::string csv =
      "name,status,frames,seconds,ate_m,surfels_with_fill,surfels_without_fill,"
      "completeness_gain,fill_rate,report,error\n";
  std::vector<std::vector<std::string>> table, links;
  long frames = 0;
  double seconds = 0;
  for (const Row& r : rows) {
    for (const std::string* f :
         {&r.name, &r.status, &r.frames, &r.seconds, &r.ate_m, &r.surfels_with, &r.surfels_without,
          &r.gain, &r.fill_rate, &r.report, &r.error})
      csv += CsvField(*f) + (f == &r.error ? "\n" : ",");
    table.push_back({r.name, r.status, r.frames, r.seconds, r.ate_m, r.surfels_with,
                     r.surfels_without, r.gain, r.fill_rate,
                     r.report.empty() ? r.error : "report"});
    links.push_back(
        {r.report.empty() ? "" : r.name + "/", "", "", "", "", "", "", "", "", r.report});
    frames += r.frames.empty() ? 0 : std::stol(r.frames);
    seconds += r.seconds.empty() ? 0 : std::stod(r.seconds);
  }
  WriteTextFileAtomically(out->File("summary.csv"), csv);
  HtmlReport html("GlassFusion batch: " + fs::path(out->dir()).filename().string());
  html.Paragraph(s.BriefReport() + "; " + std::to_string(frames) + " frames in " +
                 Fixed(seconds / 60, 1) +
                 " minutes of processing. Each capture was tracked once "
                 "and fused with and without the stereo fill (glassfusion compare).");
  html.Paragraph(
      "ATE: trajectory error in metres, where the capture has ground truth; gain: "
      "completeness (share of the observed true surface within 2 cm of the map) with "
      "the fill minus without, where the capture has a ground-truth model; fill rate: "
      "share of the keyframes' hole pixels filled.");
  html.LinkedTable({"capture", "status", "frames", "seconds", "ATE m", "surfels with fill",
                    "without", "gain", "fill rate", "report or error"},
                   table, links);
  WriteTextFileAtomically(out->File("summary.html"), html.Html());
}

}  // namespace

std::string BatchSummary::BriefReport() const {
  return std::to_string(captures) + " captures: " + std::to_string(done) + " done (" +
         std::to_string(skipped) + " of them earlier), " + std::to_string(failed) + " failed, " +
         std::to_string(pending) + " pending";
}

BatchSummary CollectBatch(const std::string& out_dir) {
  const fs::path manifest = fs::path(out_dir) / "batch" / "manifest.json";
  if (!IsRegularFile(manifest.string()))  // before the lock: no marker in a folder not a batch's
    throw InputError(manifest.string(), "missing or unreadable: is this a batch folder?");
  RunFolder::Options options;
  options.earlier = RunFolder::kKeep;
  options.shared = true;  // beside the tasks of a job array still running
  RunFolder out(out_dir, options);
  return WriteBatchSummary(&out);
}

BatchSummary WriteBatchSummary(RunFolder* out) {
  const std::string& out_dir = out->dir();
  const fs::path manifest = fs::path(out_dir) / "batch" / "manifest.json";
  const json list = ReadJsonIfAny(manifest.string());
  if (!list.is_object() || !list["captures"].is_array())
    throw InputError(manifest.string(), "missing or unreadable: is this a batch folder?");
  BatchSummary s;
  std::vector<Row> rows;
  for (const json& capture : list["captures"]) {
    rows.push_back(MakeRow(out_dir, capture));
    const std::string& status = rows.back().status;
    ++s.captures;
    s.done += status == "done";
    s.failed += status == "failed";
    s.pending += status == "pending";
  }
  WriteSummary(out, rows, s);
  return s;
}

std::string WriteSlurmScript(const BatchOptions& options) {
  std::string problem;
  if (!options.Check(&problem)) throw InputError("batch", problem);
  const std::vector<BatchCapture> captures = ReadManifest(options.manifest, options.config_file);
  const std::string dir = fs::absolute(options.out_dir).string();
  const std::unique_ptr<RunFolder> out = OpenBatchFolder(dir, options.manifest, captures, false);
  WriteBatchManifest(out.get(), captures);
  const std::string self = ExecutablePath();
  std::string array = "0-" + std::to_string(captures.size() - 1);
  if (options.slurm_max_running > 0) array += "%" + std::to_string(options.slurm_max_running);
  std::string script =
      "#!/bin/bash\n"
      "# GlassFusion batch as a Slurm job array, one capture per task (glassfusion batch "
      "--slurm).\n"
      "# Every node must see the captures, this folder and glassfusion at the same paths.\n"
      "#SBATCH --job-name=glassfusion-batch\n"
      "#SBATCH --array=" +
      array +
      "\n"
      "#SBATCH --cpus-per-task=" +
      std::to_string(options.slurm_cpus_per_task) +
      "\n"
      "#SBATCH --mem=" +
      options.slurm_memory +
      "\n"
      "#SBATCH --time=" +
      options.slurm_time +
      "\n"
      "#SBATCH --output=" +
      dir +
      "/batch/slurm-%A_%a.out\n"
      "exec '" +
      self + "' batch '" + fs::absolute(options.manifest).string() + "' --out '" + dir + "'" +
      (options.config_file.empty()
           ? ""
           : " --config '" + fs::absolute(options.config_file).string() + "'") +
      " --task \"$SLURM_ARRAY_TASK_ID\"\n";
  const std::string path = out->File("batch.sbatch");
  WriteTextFileAtomically(path, script);
  std::error_code ec;
  fs::permissions(path, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add, ec);
  return path;
}

}  // namespace gf

namespace gf {

std::string SubmitSlurmScript(const std::string& script) {
  const std::string command = "sbatch --parsable '" + script + "' 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) throw InputError(script, "cannot run sbatch");
  std::string output;
  char buffer[256];
  while (fgets(buffer, sizeof(buffer), pipe)) output += buffer;
  const int status = pclose(pipe);
  while (!output.empty() && (output.back() == '\n' || output.back() == ' ')) output.pop_back();
  if (status != 0)
    throw InputError(script, "sbatch failed" + (output.empty() ? "" : ": " + output) +
                                 " (is Slurm installed and its controller reachable?)");
  return output.substr(0, output.find(';'));  // "jobid[;cluster]"
}

}  // namespace gf
