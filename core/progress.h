// Progress on a terminal for long work. Silent when stderr is not a terminal
// (piped, CI) or when the user asked for --quiet.
#pragma once

#include <atomic>
#include <cstddef>
#include <string>

namespace scan2lod {

class Progress {
 public:
  // Global switch set by the CLI's --quiet.
  static void set_quiet(bool quiet);
  static bool enabled();

  Progress(std::string label, std::size_t total);
  ~Progress();
  // Thread-safe; prints at most every 100 ms.
  void advance(std::size_t n = 1);
  void finish();

 private:
  void draw(std::size_t done);
  std::string label_;
  std::size_t total_;
  std::atomic<std::size_t> done_{0};
  std::atomic<long long> last_draw_ms_{-1000};
  bool active_;
  bool finished_ = false;
};

}  // namespace scan2lod
