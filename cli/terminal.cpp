#include "cli/terminal.h"

#include "core/progress.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>

namespace scan2lod::cli {
namespace {
bool g_quiet = false;
}  // namespace

void set_quiet(bool quiet) {
  g_quiet = quiet;
  Progress::set_quiet(quiet);
}

bool quiet() { return g_quiet; }

void say(const char* format, ...) {
  if (g_quiet) return;
  va_list args;
  va_start(args, format);
  std::vprintf(format, args);
  va_end(args);
}

void warn(const std::string& text) {
  if (!g_quiet) std::fprintf(stderr, "scan2lod: warning: %s\n", text.c_str());
}

void Warnings::operator()(const std::string& text) {
  if (into_json_) kept_.push_back(text);
  else warn(text);
}

void install_terminal_progress() {
  if (!isatty(fileno(stderr))) return;
  set_progress_sink([](const std::string& label, double fraction, bool finished) {
    // The time left, from the pace so far of this label's work.
    using clock = std::chrono::steady_clock;
    static std::string current;
    static clock::time_point start;
    if (label != current) current = label, start = clock::now();
    const double elapsed = std::chrono::duration<double>(clock::now() - start).count();
    char eta[32] = "";
    if (!finished && fraction > 0.02 && elapsed > 1.0) {
      const long left = std::lround(elapsed * (1.0 - fraction) / fraction);
      std::snprintf(eta, sizeof eta, " %ld:%02ld left", left / 60, left % 60);
    }
    const int width = 30;
    const int filled = int(fraction * width);
    std::fprintf(stderr, "\r%-22s [%.*s%*s] %3d%%%-14s%s", label.c_str(), filled, "##############################",
                 width - filled, "", int(fraction * 100.0), eta, finished ? "\n" : "");
    std::fflush(stderr);
  });
}

}  // namespace scan2lod::cli
