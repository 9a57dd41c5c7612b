#include "core/parallel_jobs.h"

#include "core/progress.h"

#include <omp.h>

#include <exception>
#include <vector>

namespace scan2lod {

void parallel_jobs(std::size_t count, int threads, const char* label,
                   const std::function<void(std::size_t)>& work) {
  std::vector<std::exception_ptr> errors(count);
  Progress progress(label, count);
#pragma omp parallel for schedule(dynamic) num_threads(threads > 0 ? threads : omp_get_max_threads())
  for (std::size_t i = 0; i < count; ++i) {
    try {
      work(i);
    } catch (...) {
      errors[i] = std::current_exception();
    }
    progress.advance();
  }
  progress.finish();
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
}

}  // namespace scan2lod
