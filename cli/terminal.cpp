#include <scan2lod/cli/terminal.h>

#include <scan2lod/cli/exit_codes.h>
#include <scan2lod/core/error.h>
#include <scan2lod/core/progress.h>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <new>

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

namespace {

// Whether the process that started this one (an MPI launcher) writes its
// stderr to a terminal: the rank's own stderr is a pipe to it.
bool parent_stderr_is_terminal() {
  std::error_code ec;
  const std::string target =
      std::filesystem::read_symlink("/proc/" + std::to_string(getppid()) + "/fd/2", ec).string();
  return !ec && (target.rfind("/dev/pts/", 0) == 0 || target.rfind("/dev/tty", 0) == 0);
}

}  // namespace

void install_terminal_progress(bool behind_launcher) {
  if (behind_launcher ? !parent_stderr_is_terminal() : !isatty(fileno(stderr))) return;
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

int print_error(const std::string& rank) {
  const std::string who = rank.empty() ? "" : " (" + rank + ")";
  try {
    throw;
  } catch (const InputError& e) {
    std::fprintf(stderr, "scan2lod: error%s: %s\n", who.c_str(), e.what());
    return kExitInput;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "scan2lod: error%s: out of memory\n", who.c_str());
    return kExitMemory;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scan2lod: internal error%s: %s\n", who.c_str(), e.what());
    return kExitInternal;
  } catch (...) {
    std::fprintf(stderr, "scan2lod: internal error%s\n", who.c_str());
    return kExitInternal;
  }
}

}  // namespace scan2lod::cli
