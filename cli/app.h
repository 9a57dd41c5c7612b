// What both programs share: `scan2lod` (lean_main.cpp: the commands that only
// read models) and `scan2lod-full` (main.cpp: every command) set up one
// command line and run it alike.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

namespace scan2lod::cli {

// Parses and runs `argc`/`argv` with the commands `add_commands` registers;
// returns the exit code (cli/exit_codes.h).
int run_app(int argc, char** argv, const std::function<void(CLI::App&)>& add_commands);

}  // namespace scan2lod::cli
