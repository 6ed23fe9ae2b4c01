// `glassfusion batch`: its options and help, on the CLI11 app (commands.cc registers it).
#include <iostream>

#include "acquisition/errors.h"
#include "apps/commands.h"
#include "apps/interrupt.h"
#include "batch/batch.h"

namespace gf {

void AddBatchCommand(CLI::App& app) {
  auto options = std::make_shared<BatchOptions>();
  auto collect = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "batch",
      "reprocess many captures, each as `compare` does, into DIR/<name>/, and summarise them in "
      "DIR/summary.csv and DIR/summary.html; or write (and submit) a Slurm job array doing it");
  cmd->footer(
      "MANIFEST: a text file, one capture per line `PATH [--config FILE]`, or a folder whose "
      "sub-folders are captures. Each runs in DIR/<its folder name>, made unique in manifest "
      "order (x/cap, y/cap, z/cap_2 -> cap, cap_2, cap_2_2). A capture already complete with the "
      "same settings and the same files (sizes, times, index files' text) is skipped; a failed "
      "one is retried once, then reported. One batch at a time into DIR.\n"
      "Example: glassfusion batch shelf/ --out batch-out --jobs 1\n"
      "         glassfusion batch list.txt --out /shared/out --slurm --submit\n"
      "         glassfusion batch --collect /shared/out\n"
      "Writes: DIR/<name>/ (compare's outputs), DIR/batch/ (each capture's log and state), "
      "DIR/summary.csv, DIR/summary.html; with --slurm DIR/batch.sbatch.");
  cmd->add_option("MANIFEST", options->manifest, "manifest file, or folder of captures");
  cmd->add_option("--out", options->out_dir, "batch folder");
  cmd->add_option("--jobs", options->jobs,
                  "captures processed at once on this machine; each uses 2 threads, yet on 2 "
                  "cores 2 at once measured 1.9x faster than 1 (the stages wait on each other); "
                  "each may take about 2 GB")
      ->capture_default_str();
  cmd->add_option("--config", options->config_file,
                  "JSON settings for captures whose manifest line names none");
  cmd->add_option("--task", options->task,
                  "process only capture I (0-based), as one task of a Slurm job array");
  cmd->add_flag("--slurm", options->slurm,
                "write DIR/batch.sbatch, a Slurm job array with one capture per task");
  cmd->add_flag("--submit", options->submit, "with --slurm: submit it with sbatch");
  cmd->add_option("--max-running", options->slurm_max_running,
                  "with --slurm: tasks running at once (the array's %K; 0 = no limit)");
  cmd->add_option("--cpus-per-task", options->slurm_cpus_per_task, "with --slurm: cores per task")
      ->capture_default_str();
  cmd->add_option("--mem", options->slurm_memory, "with --slurm: memory per task")
      ->capture_default_str();
  cmd->add_option("--time", options->slurm_time, "with --slurm: time limit per task")
      ->capture_default_str();
  cmd->add_option("--collect", *collect,
                  "build DIR's summary from whatever captures have finished (Slurm)");
  cmd->callback([options, collect] {
    if (!collect->empty()) {
      const BatchSummary s = CollectBatch(*collect);
      std::cout << "batch: " << s.BriefReport() << "; " << *collect << "/summary.html" << std::endl;
      return;
    }
    if (options->slurm) {
      const std::string script = WriteSlurmScript(*options);
      std::cout << "batch: wrote " << script;
      if (options->submit) std::cout << "; submitted as job " << SubmitSlurmScript(script);
      std::cout << std::endl;
      return;
    }
    const InterruptHandler interrupt;
    options->interrupt = interrupt.signal();
    const BatchSummary s = RunBatch(*options);
    std::cout << "batch: " << s.BriefReport() << "; " << options->out_dir << "/summary.html"
              << std::endl;
    if (s.failed > 0 && options->task < 0)
      throw InputError(options->out_dir,
                       std::to_string(s.failed) + " captures failed (see summary.html and batch/)");
  });
}

}  // namespace gf
