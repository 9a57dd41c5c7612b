#include <scan2lod/core/large_array.h>

#include <cstdint>

#include <sys/mman.h>

namespace scan2lod {

namespace {

constexpr std::size_t kBlock = std::size_t(2) << 20;

std::size_t whole_blocks(std::size_t bytes) { return (bytes + kBlock - 1) & ~(kBlock - 1); }

}  // namespace

void* allocate_large(std::size_t bytes) {
  const std::size_t length = whole_blocks(bytes);
  if (length < bytes) throw std::bad_alloc();
  // One block more than needed, then the unaligned head and the tail unmapped.
  void* mapped = ::mmap(nullptr, length + kBlock, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (mapped == MAP_FAILED) throw std::bad_alloc();
  const std::uintptr_t begin = reinterpret_cast<std::uintptr_t>(mapped);
  const std::uintptr_t aligned = (begin + kBlock - 1) & ~std::uintptr_t(kBlock - 1);
  if (aligned > begin) ::munmap(mapped, aligned - begin);
  if (const std::size_t tail = begin + length + kBlock - (aligned + length); tail > 0)
    ::munmap(reinterpret_cast<void*>(aligned + length), tail);
  ::madvise(reinterpret_cast<void*>(aligned), length, MADV_HUGEPAGE);  // a hint: failure is harmless
  return reinterpret_cast<void*>(aligned);
}

void free_large(void* data, std::size_t bytes) { ::munmap(data, whole_blocks(bytes)); }

}  // namespace scan2lod
