// Seconds of wall-clock time between laps: the stage times that reports give.
#pragma once

#include <chrono>

namespace scan2lod {

class Stopwatch {
 public:
  // Seconds since the last lap (or since construction), and starts the next.
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return s;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

}  // namespace scan2lod
