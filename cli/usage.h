// Usage errors (exit code 2) said one way, whichever rule caught them: CLI11's
// own, a mistyped command, or a flag the command checks itself.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

namespace scan2lod::cli {

// CLI11's failure message with the "scan2lod: error: " every other error has,
// and the --help of the command that failed.
std::string usage_failure_message(const CLI::App* app, const CLI::Error& e);

// The word in `argv` where `app`'s command should be, when it names none of
// its commands: "unknown command 'W'", with the nearest command's name when one
// is close enough to be a typo. Empty when the command is known or absent.
std::string unknown_command_message(const CLI::App& app, int argc, char** argv);

// Adds -j/--threads to `cmd`. A negative count is a usage error; a count above
// the machine's cores is lowered to them, with a warning, by usable_threads().
CLI::Option* add_threads_option(CLI::App* cmd, int* threads);

// `threads` as the work should run it: at most the machine's cores, saying so
// when lowered (0, all cores, is kept).
int usable_threads(int threads);

}  // namespace scan2lod::cli
