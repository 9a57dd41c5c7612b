#include "io/atomic_file.h"

#include "core/error.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <system_error>

namespace scan2lod {

namespace fs = std::filesystem;

void check_output_path(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw InputError(path, "is a folder; expected a file name to write");
  const fs::path folder = fs::path(path).parent_path();
  const fs::path dir = folder.empty() ? fs::path(".") : folder;
  if (!fs::is_directory(dir, ec))
    throw InputError(path, "cannot write: folder " + dir.string() + " does not exist");
  if (::access(dir.c_str(), W_OK) != 0)
    throw InputError(path, "cannot write into folder " + dir.string() + ": " + std::strerror(errno));
}

void write_atomically(const std::string& path,
                      const std::function<void(const std::string&)>& write) {
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
  // rename(2) itself, so that the message is its errno, not a wrapper's.
  if (std::rename(tmp.c_str(), target.c_str()) != 0) {
    const int err = errno;
    std::error_code ec;
    fs::remove(tmp, ec);
    std::string reason = std::strerror(err);
    if (fs::is_directory(target, ec)) reason = "a folder of that name is in the way";
    throw InputError(path, "cannot move the finished file into place: " + reason);
  }
}

}  // namespace scan2lod
