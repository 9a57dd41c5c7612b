// Open-addressing hash of indices into an array of 64-bit keys that its
// owner holds: 4 bytes a slot where FlatHashMap takes 12, for tables of tens
// of millions. The weld's leaves by cube took 768 MiB as a FlatHashMap at
// 10^8 points (28 M leaves in 2^26 slots), a quarter of its peak; 256 MiB so.
#pragma once

#include <scan2lod/core/flat_hash.h>

#include <cassert>
#include <cstdint>
#include <vector>

namespace scan2lod {

class IndexHash {
 public:
  // `keys` outlives the hash and may grow; index i stands for (*keys)[i],
  // which must not change while i is in the hash.
  explicit IndexHash(const std::vector<std::uint64_t>* keys = nullptr, std::size_t expected = 0) : keys_(keys) {
    std::size_t capacity = 16;
    while (capacity < expected * 2) capacity *= 2;
    slots_.assign(capacity, kEmpty);
  }

  // The index whose key is `key`, or -1.
  std::int32_t find(std::uint64_t key) const {
    for (std::size_t i = slot(key);; i = (i + 1) & (slots_.size() - 1)) {
      const std::int32_t at = slots_[i];
      if (at == kEmpty) return -1;
      if ((*keys_)[std::size_t(at)] == key) return at;
    }
  }

  // Adds index i, whose key is not in the hash yet.
  void insert(std::int32_t i) {
    if ((size_ + 1) * 2 > slots_.size()) grow();
    place(i);
    ++size_;
  }

  std::size_t size() const { return size_; }

 private:
  static constexpr std::int32_t kEmpty = -1;

  std::size_t slot(std::uint64_t key) const { return std::size_t(mix_key(key)) & (slots_.size() - 1); }
  void place(std::int32_t i) {
    std::size_t s = slot((*keys_)[std::size_t(i)]);
    while (slots_[s] != kEmpty) s = (s + 1) & (slots_.size() - 1);
    slots_[s] = i;
  }
  void grow() {
    std::vector<std::int32_t> old(slots_.size() * 2, kEmpty);
    old.swap(slots_);
    for (std::int32_t i : old)
      if (i != kEmpty) place(i);
  }

  const std::vector<std::uint64_t>* keys_;
  std::vector<std::int32_t> slots_;
  std::size_t size_ = 0;
};

}  // namespace scan2lod
