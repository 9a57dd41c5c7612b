#include <scan2lod/core/parallel_jobs.h>

#include <scan2lod/core/progress.h>

#include <omp.h>

#include <exception>
#include <vector>

namespace scan2lod {

void parallel_jobs(std::size_t count, int threads, Progress* progress, const std::function<void(std::size_t)>& work) {
  std::vector<std::exception_ptr> errors(count);
#pragma omp parallel for schedule(dynamic) num_threads(threads > 0 ? threads : omp_get_max_threads())
  for (std::size_t i = 0; i < count; ++i) {
    try {
      work(i);
    } catch (...) {
      errors[i] = std::current_exception();
    }
    progress->advance();
  }
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
}

void parallel_jobs(std::size_t count, int threads, const char* label,
                   const std::function<void(std::size_t)>& work) {
  Progress progress(label, count);
  parallel_jobs(count, threads, &progress, work);
  progress.finish();
}

}  // namespace scan2lod
