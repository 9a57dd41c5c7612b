#include <scan2lod/cli/full_program.h>

#include <scan2lod/cli/exit_codes.h>

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>

namespace scan2lod::cli {
namespace {

namespace fs = std::filesystem;

bool ends_with_vtp(std::string word) {
  std::transform(word.begin(), word.end(), word.begin(), [](unsigned char c) { return std::tolower(c); });
  return word.size() >= 4 && word.compare(word.size() - 4, 4, ".vtp") == 0;
}

}  // namespace

bool needs_full_program(int argc, char** argv) {
  const char* command = nullptr;
  for (int i = 1; i < argc && !command; ++i)
    if (argv[i][0] != '-') command = argv[i];  // the options before a command take no value
  if (!command) return true;
  const std::string name = command;
  if (name != "info" && name != "extract" && name != "export" && name != "serve") return true;
  for (int i = 1; i < argc; ++i)
    if (ends_with_vtp(argv[i])) return true;
  return false;
}

int run_full_program(int argc, char** argv) {
  (void)argc;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  const fs::path beside = self.parent_path() / "scan2lod-full";
  const fs::path installed = self.parent_path().parent_path() / "libexec" / "scan2lod" / "scan2lod-full";
  for (const fs::path& full : {beside, installed}) {
    if (ec || !fs::exists(full)) continue;
    ::execv(full.c_str(), argv);
    std::fprintf(stderr, "scan2lod: error: cannot run %s: %s\n", full.c_str(), std::strerror(errno));
    return kExitInternal;
  }
  std::fprintf(stderr,
               "scan2lod: error: this command runs in scan2lod-full, which is neither beside this program (%s) nor "
               "in %s: reinstall scan2lod\n",
               beside.c_str(), installed.c_str());
  return kExitInternal;
}

}  // namespace scan2lod::cli
