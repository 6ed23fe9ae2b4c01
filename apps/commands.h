// Registers every `glassfusion` subcommand on the CLI11 app. Each subcommand's callback runs the
// command and throws gf::InputError on bad input (main turns that into exit code 2).
#pragma once

#include <CLI/CLI.hpp>

namespace gf {

void RegisterCommands(CLI::App& app);
// `batch` (batch_command.cc), registered by RegisterCommands.
void AddBatchCommand(CLI::App& app);
// `fill-frame` (fill_frame_command.cc), registered by RegisterCommands.
void AddFillFrameCommand(CLI::App& app);

}  // namespace gf
