#include <scan2lod/python/progress.h>

namespace scan2lod::python {
namespace py = pybind11;

std::unique_lock<std::mutex> take_turn() {
  static std::mutex turns;
  // Waiting with the GIL would stop the thread whose turn it is at its next callback.
  py::gil_scoped_release released;
  return std::unique_lock<std::mutex>(turns);
}

CallbackProgress::CallbackProgress(py::object callback) : callback_(std::move(callback)), previous_(progress_sink()) {
  if (callback_.is_none()) {
    set_progress_sink({});
    return;
  }
  if (!PyCallable_Check(callback_.ptr())) throw py::type_error("progress must be callable as progress(stage, fraction)");
  set_progress_sink([this](const std::string& stage, double fraction, bool) { call(stage, fraction); });
}

CallbackProgress::~CallbackProgress() { set_progress_sink(std::move(previous_)); }

void CallbackProgress::call(const std::string& stage, double fraction) {
  if (failed_) return;
  // From whichever thread advanced the work; Python needs the GIL.
  py::gil_scoped_acquire gil;
  if (failed_) return;
  try {
    callback_(stage, fraction);
  } catch (py::error_already_set& e) {
    failed_ = true;
    error_type_ = e.type();
    error_value_ = e.value();
    error_trace_ = e.trace();
  }
}

void CallbackProgress::raise_if_failed() {
  if (!failed_) return;
  PyErr_Restore(error_type_.release().ptr(), error_value_.release().ptr(), error_trace_.release().ptr());
  throw py::error_already_set();
}

}  // namespace scan2lod::python
