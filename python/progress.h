// The library's progress (core/progress.h) forwarded to a Python callable,
// called as callback(stage, fraction) with the GIL held, while the work runs
// with the GIL released. The library cannot be stopped midway: an exception
// the callback raises mutes it, and is raised once the work has returned.
//
// The library's sink is one for the process, and may not change while work
// reports to it; so calls that report progress run one at a time (each
// uses every core already), whichever Python threads make them.
#pragma once

#include <scan2lod/core/progress.h>

#include <pybind11/pybind11.h>

#include <atomic>
#include <mutex>
#include <type_traits>

namespace scan2lod::python {

class CallbackProgress {
 public:
  // Installs a sink that calls `callback` (None: no sink, the work is
  // silent); the sink installed before comes back at destruction. Construct
  // and destroy with the GIL held.
  explicit CallbackProgress(pybind11::object callback);
  ~CallbackProgress();
  CallbackProgress(const CallbackProgress&) = delete;
  CallbackProgress& operator=(const CallbackProgress&) = delete;

  // Raises what the callback raised, if it did. With the GIL held.
  void raise_if_failed();

 private:
  void call(const std::string& stage, double fraction);
  pybind11::object callback_;
  ProgressSink previous_;
  std::atomic<bool> failed_{false};
  pybind11::object error_type_, error_value_, error_trace_;
};

// Waits (with the GIL released) until no other call reports progress, and
// holds that turn until the lock is released. With the GIL held.
std::unique_lock<std::mutex> take_turn();

// Runs `work` with the GIL released and `callback` (or None) receiving its
// progress; raises what the callback raised.
template <typename Work>
auto with_progress(pybind11::object callback, Work&& work) -> decltype(work()) {
  const std::unique_lock<std::mutex> turn = take_turn();
  CallbackProgress progress(std::move(callback));
  if constexpr (std::is_void_v<decltype(work())>) {
    {
      pybind11::gil_scoped_release released;
      work();
    }
    progress.raise_if_failed();
  } else {
    auto result = [&] {
      pybind11::gil_scoped_release released;
      return work();
    }();
    progress.raise_if_failed();
    return result;
  }
}

}  // namespace scan2lod::python
