// What the command line shows: results on stdout, progress bars on stderr when
// it is a terminal, errors on stderr. --quiet silences all but errors and the
// JSON a command was asked for with --json.
#pragma once

#include <string>
#include <vector>

namespace scan2lod::cli {

void set_quiet(bool quiet);
bool quiet();

// printf to stdout unless --quiet.
void say(const char* format, ...) __attribute__((format(printf, 1, 2)));

// "scan2lod: warning: TEXT" on stderr unless --quiet.
void warn(const std::string& text);

// The warnings of a command that answers --json: on stderr as they come (as
// warn()), or with --json kept for the object's "warnings", so that its output
// stays one parseable object even with stderr merged into it.
class Warnings {
 public:
  explicit Warnings(bool into_json) : into_json_(into_json) {}
  void operator()(const std::string& text);
  const std::vector<std::string>& kept() const { return kept_; }

 private:
  bool into_json_;
  std::vector<std::string> kept_;
};

// Draws the library's progress (core/progress.h) as a bar on stderr, only when
// stderr is a terminal and --quiet was not given. Under an MPI launcher a
// rank's stderr is a pipe to the launcher even when the user watches a
// terminal: `behind_launcher` asks whether the launcher's (the parent
// process's) stderr is a terminal instead. (OpenMPI gives the ranks a
// pseudo-terminal for stdout whatever the launcher's is, so stdout says
// nothing.)
void install_terminal_progress(bool behind_launcher = false);

// Prints the error being handled (call it in a catch block) as
// "scan2lod: error: WHAT" on stderr, naming `rank` when it is not empty, and
// returns the exit code of its kind (exit_codes.h).
int print_error(const std::string& rank = "");

}  // namespace scan2lod::cli
