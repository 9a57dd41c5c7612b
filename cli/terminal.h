// What the command line shows: results on stdout, progress bars on stderr when
// it is a terminal, errors on stderr. --quiet silences all but errors and the
// JSON a command was asked for with --json.
#pragma once

#include <string>

namespace scan2lod::cli {

void set_quiet(bool quiet);
bool quiet();

// printf to stdout unless --quiet.
void say(const char* format, ...) __attribute__((format(printf, 1, 2)));

// "scan2lod: warning: TEXT" on stderr unless --quiet.
void warn(const std::string& text);

// Draws the library's progress (core/progress.h) as a bar on stderr, only when
// stderr is a terminal and --quiet was not given.
void install_terminal_progress();

}  // namespace scan2lod::cli
