#include "io/atomic_file.h"

#include "core/error.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <system_error>

namespace scan2lod {

void write_atomically(const std::string& path,
                      const std::function<void(const std::string&)>& write) {
  namespace fs = std::filesystem;
  fs::path target(path);
  // Keep the extension last: writers pick the format from it.
  fs::path tmp = target.parent_path() /
                 (".tmp-" + std::to_string(::getpid()) + "-" + target.filename().string());
  try {
    write(tmp.string());
    if (!fs::exists(tmp)) throw InputError(path, "writer produced no output");
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
  std::error_code ec;
  fs::rename(tmp, target, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw InputError(path, "cannot move the finished file into place: " + ec.message());
  }
}

}  // namespace scan2lod
