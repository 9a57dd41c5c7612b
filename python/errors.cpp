#include <scan2lod/python/errors.h>

#include <filesystem>

namespace scan2lod::python {
namespace py = pybind11;
namespace {

[[noreturn]] void raise(PyObject* type, const std::string& message) {
  // Message only: OSError(errno, strerror, filename) would print as
  // "[Errno 2] ...", not as the command line's text. The message names the file.
  PyErr_SetString(type, message.c_str());
  throw py::error_already_set();
}

bool exists(const std::string& path) {
  std::error_code ec;
  return std::filesystem::exists(path, ec);
}

}  // namespace

void register_error_translation(py::module_& m) {
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const InputError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });
}

void raise_read_error(const InputError& error, const std::vector<std::string>& paths) {
  const std::string message = error.what();
  for (const std::string& path : paths)
    if (message.rfind(path + ": ", 0) == 0 && !exists(path)) raise(PyExc_FileNotFoundError, message);
  raise(PyExc_ValueError, message);
}

void raise_write_error(const InputError& error, const std::string& path, bool written) {
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  std::error_code ec;
  if (!folder.empty() && !std::filesystem::is_directory(folder, ec)) raise(PyExc_FileNotFoundError, error.what());
  raise(written ? PyExc_OSError : PyExc_ValueError, error.what());
}

}  // namespace scan2lod::python
