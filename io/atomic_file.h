// Outputs are written to a temporary file beside the target and renamed into
// place, so a failure never leaves a half-written file under the real name.
#pragma once

#include <functional>
#include <string>

namespace scan2lod {

// Calls write(tmp_path) and renames tmp_path to path. If write throws, the
// temporary file is removed and the exception propagates.
void write_atomically(const std::string& path,
                      const std::function<void(const std::string& tmp_path)>& write);

}  // namespace scan2lod
