// The library's InputError ("FILE: WHAT", core/error.h) as Python exceptions,
// the message unchanged (the command line prints the same text after
// "scan2lod: error: "):
//   FileNotFoundError  FILE is a path the caller gave, and it is not there
//   OSError            a write failed (the folder is there, the path is fine)
//   ValueError         everything else: bad arguments, unreadable or
//                      malformed content, data with no surface, a request a
//                      model does not offer
// A plain InputError thrown through pybind11 becomes ValueError (the
// translator registered by register_error_translation()); calls that read or
// write paths catch it first with reading_files() and writing_file().
#pragma once

#include <scan2lod/core/error.h>

#include <pybind11/pybind11.h>

#include <string>
#include <vector>

namespace scan2lod::python {

void register_error_translation(pybind11::module_& m);

// Raises (as a pending Python error, then pybind11::error_already_set) what
// `error`, thrown by a call that read `paths`, stands for.
[[noreturn]] void raise_read_error(const InputError& error, const std::vector<std::string>& paths);

// Runs `work` (a call that reads `paths`), turning InputError into the above.
// The GIL must be held when `work` returns or throws.
template <typename Work>
auto reading_files(const std::vector<std::string>& paths, Work&& work) -> decltype(work()) {
  try {
    return work();
  } catch (const InputError& e) {
    raise_read_error(e, paths);
  }
}

// Raises what `error`, thrown while writing `path`, stands for: by the
// check before the write (`written` false) or by the write.
[[noreturn]] void raise_write_error(const InputError& error, const std::string& path, bool written);

// Runs `check` (which throws InputError unless `path` could be written:
// check_mesh_output, check_model_output), then `write`: FileNotFoundError
// when the folder is missing, ValueError for a path refused by `check` (an
// unknown extension), OSError when the write itself fails.
template <typename Check, typename Write>
void writing_file(const std::string& path, Check&& check, Write&& write) {
  try {
    check();
  } catch (const InputError& e) {
    raise_write_error(e, path, false);
  }
  try {
    write();
  } catch (const InputError& e) {
    raise_write_error(e, path, true);
  }
}

}  // namespace scan2lod::python
