// Progress of long library work, reported through a callback that the program
// installs: the command line draws a bar on a terminal (cli/terminal.h); a
// library user may forward it to a GUI or a log. With no sink, work is silent.
#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <string>

namespace scan2lod {

// Called with a stage's label and how far it is (0 to 1); `finished` once at
// the end. Calls come from whichever thread advanced the work, at most about
// every 100 ms per stage, never two at once for one stage.
using ProgressSink = std::function<void(const std::string& label, double fraction, bool finished)>;

// Installs `sink` for all later stages (an empty function removes it). Not
// thread-safe against running work: set it before starting.
void set_progress_sink(ProgressSink sink);
// The sink installed now (empty when none), so that a caller can wrap it.
ProgressSink progress_sink();

class Progress {
 public:
  // Mutes the sink without removing it (the command line's --quiet, benches).
  static void set_quiet(bool quiet);
  // A sink is installed and not muted.
  static bool enabled();

  Progress(std::string label, std::size_t total);
  ~Progress();
  // Thread-safe.
  void advance(std::size_t n = 1);
  void finish();

 private:
  void report(std::size_t done, bool finished);
  std::string label_;
  std::size_t total_;
  std::atomic<std::size_t> done_{0};
  std::atomic<long long> last_report_ms_{-1000};
  bool active_;
  bool finished_ = false;
};

}  // namespace scan2lod
