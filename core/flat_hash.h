// Open-addressing hash map from 64-bit keys to 32-bit values, in two flat arrays.
// The sparse grids here key corners, cubes and edges by packed integer
// coordinates; std::unordered_map's node per entry costs more than the work.
#pragma once

#include <algorithm>
#include <cassert>
#include <cstdint>
#include <vector>

namespace scan2lod {

// splitmix64's finalizer: packed coordinates are far from uniform, and the
// tables take their low bits.
inline std::uint64_t mix_key(std::uint64_t key) {
  key ^= key >> 30;
  key *= 0xbf58476d1ce4e5b9ull;
  key ^= key >> 27;
  key *= 0x94d049bb133111ebull;
  key ^= key >> 31;
  return key;
}

class FlatHashMap {
 public:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t(0);

  explicit FlatHashMap(std::size_t expected = 16) { rehash(capacity_for(expected)); }

  std::size_t size() const { return size_; }
  std::size_t capacity() const { return keys_.size(); }  // slots

  // Returns the value for key, or -1.
  std::int32_t find(std::uint64_t key) const {
    assert(key != kEmpty);
    for (std::size_t i = slot(key);; i = (i + 1) & mask_) {
      if (keys_[i] == key) return values_[i];
      if (keys_[i] == kEmpty) return -1;
    }
  }

  // Inserts key -> value unless key is present; returns the stored value.
  std::int32_t insert(std::uint64_t key, std::int32_t value) {
    assert(key != kEmpty);
    if ((size_ + 1) * 2 > keys_.size()) rehash(keys_.size() * 2);
    for (std::size_t i = slot(key);; i = (i + 1) & mask_) {
      if (keys_[i] == key) return values_[i];
      if (keys_[i] == kEmpty) {
        keys_[i] = key;
        values_[i] = value;
        ++size_;
        return value;
      }
    }
  }

  // Sets key -> value, inserting key if needed.
  void assign(std::uint64_t key, std::int32_t value) {
    assert(key != kEmpty);
    if ((size_ + 1) * 2 > keys_.size()) rehash(keys_.size() * 2);
    for (std::size_t i = slot(key);; i = (i + 1) & mask_) {
      if (keys_[i] == key) {
        values_[i] = value;
        return;
      }
      if (keys_[i] == kEmpty) {
        keys_[i] = key;
        values_[i] = value;
        ++size_;
        return;
      }
    }
  }

  // Starts loading key's home slot, for a find() a little later.
  void prefetch(std::uint64_t key) const {
    const std::size_t i = slot(key);
    __builtin_prefetch(keys_.data() + i);
    __builtin_prefetch(values_.data() + i);
  }

  // Empties the map, keeping its room.
  void clear() {
    std::fill(keys_.begin(), keys_.end(), kEmpty);
    size_ = 0;
  }

  void reserve(std::size_t n) {
    if (capacity_for(n) > keys_.size()) rehash(capacity_for(n));
  }

 private:
  static std::size_t capacity_for(std::size_t n) {
    std::size_t c = 16;
    while (c < n * 2) c *= 2;
    return c;
  }
  std::size_t slot(std::uint64_t key) const { return std::size_t(mix_key(key)) & mask_; }
  void rehash(std::size_t capacity) {
    std::vector<std::uint64_t> old_keys(capacity, kEmpty);
    std::vector<std::int32_t> old_values(capacity);
    old_keys.swap(keys_);
    old_values.swap(values_);
    mask_ = capacity - 1;
    size_ = 0;
    for (std::size_t i = 0; i < old_keys.size(); ++i)
      if (old_keys[i] != kEmpty) insert(old_keys[i], old_values[i]);
  }

  std::vector<std::uint64_t> keys_;
  std::vector<std::int32_t> values_;
  std::size_t mask_ = 0;
  std::size_t size_ = 0;
};

}  // namespace scan2lod
