// Outputs are written to a temporary file beside the target and renamed into
// place, so a failure never leaves a half-written file under the real name.
#pragma once

#include <functional>
#include <string>

namespace scan2lod {

// Calls write(tmp_path) and renames tmp_path to path. If write throws, the
// temporary file is removed and the exception propagates.
// A failed rename names the system's reason (and the path).
void write_atomically(const std::string& path,
                      const std::function<void(const std::string& tmp_path)>& write);

// Throws InputError unless a file can be created at `path`: its folder exists
// and is writable, and `path` is not itself a folder.
void check_output_path(const std::string& path);

}  // namespace scan2lod
