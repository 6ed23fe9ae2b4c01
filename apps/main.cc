// The `glassfusion` command line: subcommand dispatch (DESIGN.md, "Command line contract").
//
// Exit codes: 0 success, 1 internal error, 2 bad input, an output that cannot be written, or
// usage (one line "error: <file>: <problem>"), 128 + N when stopped by signal N after writing a
// partial run (130 for Ctrl-C).
#include <malloc.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>

#include "acquisition/errors.h"
#include "apps/commands.h"
#include "apps/interrupt.h"
#include "apps/progress.h"
#include "report/run_report.h"

int main(int argc, char** argv) {
  // Every keyframe pair allocates and frees tens of megabytes (images, cost volumes). glibc would
  // hand blocks above its mmap threshold back to the kernel on free and fault them in again on the
  // next pair; keeping freed memory in the heap instead cut the one-core stereo time of an ICL pair
  // from 160 to 112 ms on our 2-core VM. The process keeps its peak heap.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's largest allowed threshold (64-bit)
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  gf::ShowProgressOnTerminal();  // the libraries' long work, drawn on stderr
  gf::SetCommandLine(argc, argv);  // for the reports' "command" line
  // stdout carries results (JSON for info); logs go to stderr.
  spdlog::set_default_logger(spdlog::stderr_color_mt("glassfusion"));
  spdlog::set_pattern("[%l] %v");
  spdlog::set_level(spdlog::level::warn);
  CLI::App app{
      "GlassFusion: RGB-D scanning of scenes with glass and shiny objects; fills depth holes with "
      "stereo between keyframes."};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("glassfusion ") + GF_VERSION);
  // -v and --quiet are accepted before and after the subcommand (fallthrough).
  bool verbose = false, quiet = false;
  app.add_flag("-v,--verbose", verbose, "log each stage's decisions");
  app.add_flag("-q,--quiet", quiet, "log errors only");
  app.fallthrough();
  app.parse_complete_callback([&] {
    if (verbose) spdlog::set_level(spdlog::level::debug);
    if (quiet) spdlog::set_level(spdlog::level::err);
  });
  gf::RegisterCommands(app);
  for (CLI::App* sub : app.get_subcommands({})) sub->fallthrough();
  if (argc == 1) {  // no arguments: the usage, as an error
    std::fprintf(stderr, "%s", app.help().c_str());
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const gf::Interrupted& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 128 + e.signal();
  } catch (const gf::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "internal error: %s\n", e.what());
    return 1;
  }
  return 0;
}
