// A sort on two threads that leaves no thread behind.
#pragma once

#include <algorithm>
#include <thread>

namespace scan2lod {

// Sorts [first, last) by `less`, a total order (so the result is the same on
// any core count): on two threads when asked and worth it, halves sorted
// apart and merged. Not __gnu_parallel::sort: its OpenMP workers spin for a
// while after each sort, on the cores the next stage's threads want (the
// cluster hierarchy calls it hundreds of times between its own threads'
// work: 11-13 % of a bunny build's CPU time, spinning).
template <class It, class Less>
void sort_on_cores(It first, It last, int threads, Less less) {
  const auto n = last - first;
  if (threads < 2 || n < (1 << 16)) {
    std::sort(first, last, less);
    return;
  }
  const It middle = first + n / 2;
  std::thread other([&] { std::sort(first, middle, less); });
  std::sort(middle, last, less);
  other.join();
  std::inplace_merge(first, middle, last, less);
}

}  // namespace scan2lod
