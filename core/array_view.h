// A read-only view of a flat array (C++17 has no std::span), so that a
// function reads a std::vector and a LargeArray (core/large_array.h) alike.
#pragma once

#include <cstddef>
#include <vector>

namespace scan2lod {

template <class T>
class ArrayView {
 public:
  ArrayView() = default;
  ArrayView(const T* data, std::size_t size) : data_(data), size_(size) {}
  template <class Allocator>
  ArrayView(const std::vector<T, Allocator>& v) : data_(v.data()), size_(v.size()) {}  // NOLINT: implicit by design

  const T* data() const { return data_; }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  const T* begin() const { return data_; }
  const T* end() const { return data_ + size_; }

 private:
  const T* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace scan2lod
