// Vectors for the large flat arrays a model holds (octree nodes, transitions,
// vertices): their memory comes in whole 2 MB blocks, aligned and advised for
// transparent huge pages. On these machines the first touch of a 4 KB page is
// a fault that costs about 13 us (50 MB: 166 ms in 4 KB pages, 5 ms in huge
// pages), and a loaded model is some 60 MB of freshly touched arrays; malloc's
// own mappings are not 2 MB aligned, so advising them afterwards covers only
// their inner blocks.
#pragma once

#include <cstddef>
#include <new>
#include <vector>

namespace scan2lod {

// Arrays under this many bytes come from operator new: rounding them up to a
// 2 MB block would waste more than it saves.
constexpr std::size_t kLargeArrayBytes = std::size_t(1) << 20;

// Whole 2 MB blocks for `bytes` (>= kLargeArrayBytes), aligned, advised for
// huge pages; throws std::bad_alloc when the system refuses.
void* allocate_large(std::size_t bytes);
void free_large(void* data, std::size_t bytes);

template <class T>
struct LargeArrayAllocator {
  using value_type = T;

  LargeArrayAllocator() = default;
  template <class U>
  LargeArrayAllocator(const LargeArrayAllocator<U>&) noexcept {}

  T* allocate(std::size_t n) {
    if (n > std::size_t(-1) / sizeof(T)) throw std::bad_array_new_length();
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kLargeArrayBytes) return static_cast<T*>(::operator new(bytes, std::align_val_t(alignof(T))));
    return static_cast<T*>(allocate_large(bytes));
  }
  void deallocate(T* p, std::size_t n) noexcept {
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kLargeArrayBytes)
      ::operator delete(p, std::align_val_t(alignof(T)));
    else
      free_large(p, bytes);
  }

  template <class U>
  bool operator==(const LargeArrayAllocator<U>&) const noexcept { return true; }
  template <class U>
  bool operator!=(const LargeArrayAllocator<U>&) const noexcept { return false; }
};

template <class T>
using LargeArray = std::vector<T, LargeArrayAllocator<T>>;

}  // namespace scan2lod
