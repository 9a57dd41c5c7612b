// Independent jobs (one per input file) on all cores, with progress and with
// errors carried out of the worker threads.
#pragma once

#include <cstddef>
#include <functional>

namespace scan2lod {

// Runs work(i) for every i in [0, count) on `threads` threads (0: all cores),
// showing progress as `label`. After all jobs ran, the exception of the
// lowest-numbered failed job, if any, is rethrown.
void parallel_jobs(std::size_t count, int threads, const char* label,
                   const std::function<void(std::size_t)>& work);
// The same, advancing `progress` (a stage of more jobs than these) instead.
class Progress;
void parallel_jobs(std::size_t count, int threads, Progress* progress, const std::function<void(std::size_t)>& work);

}  // namespace scan2lod
