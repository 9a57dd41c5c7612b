// What several test files share: running the real scan2lod binary, and a
// scratch folder per test process that is removed when the process exits.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <sys/wait.h>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

#include <unistd.h>

namespace scan2lod::testing {

struct CliRun {
  int status;          // as returned by pclose; 0 on success
  std::string output;  // stdout, and stderr unless it was dropped
};

// Runs a shell command line, collecting what it prints to stdout.
inline CliRun run_shell(const std::string& command) {
  CliRun r{-1, ""};
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buffer;
  std::size_t n;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) r.output.append(buffer.data(), n);
  r.status = pclose(pipe);
  return r;
}

// Runs `scan2lod ARGS` through the shell.
inline CliRun run_cli(const std::string& args, bool merge_stderr = true) {
  return run_shell(std::string(SCAN2LOD_CLI) + " " + args + (merge_stderr ? " 2>&1" : " 2>/dev/null"));
}

// The exit code of a run, or -1 when it did not exit (a signal).
inline int exit_code(const CliRun& r) { return WIFEXITED(r.status) ? WEXITSTATUS(r.status) : -1; }

// This process's scratch folder (created on first use, removed at exit).
inline std::filesystem::path scratch_folder() {
  struct Folder {
    std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("scan2lod_test_" + std::to_string(::getpid()));
    ~Folder() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Folder folder;
  std::filesystem::create_directories(folder.path);
  return folder.path;
}

// A named folder inside it, for one test file's outputs.
inline std::filesystem::path scratch_folder(const std::string& name) {
  const std::filesystem::path dir = scratch_folder() / name;
  std::filesystem::create_directories(dir);
  return dir;
}

// Whether there is an X display to render on (tests run under xvfb-run).
inline bool have_display() {
  const char* d = std::getenv("DISPLAY");
  return d && *d;
}

// The bundled bunny scans' .conf.
inline std::string bunny_scans() { return std::string(SCAN2LOD_SOURCE_DIR) + "/data/bunny/bun.conf"; }

// The bundled bunny's model at R = 64, built once per test process by
// `scan2lod build`.
inline const std::filesystem::path& bunny_model() {
  static const std::filesystem::path path = [] {
    const std::filesystem::path p = scratch_folder("models") / "bunny64.mco";
    const CliRun r = run_cli("build " + bunny_scans() + " -o " + p.string() + " -r 64 -q");
    EXPECT_EQ(r.status, 0) << r.output;
    return p;
  }();
  return path;
}

}  // namespace scan2lod::testing
