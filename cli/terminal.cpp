#include "cli/terminal.h"

#include "core/progress.h"

#include <unistd.h>

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

void install_terminal_progress() {
  if (!isatty(fileno(stderr))) return;
  set_progress_sink([](const std::string& label, double fraction, bool finished) {
    const int width = 30;
    const int filled = int(fraction * width);
    std::fprintf(stderr, "\r%-22s [%.*s%*s] %3d%%%s", label.c_str(), filled, "##############################",
                 width - filled, "", int(fraction * 100.0), finished ? "\n" : "");
    std::fflush(stderr);
  });
}

}  // namespace scan2lod::cli
