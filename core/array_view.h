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

// A read-only view of a flat array followed by a vector that grows: the
// cluster hierarchy reads the model's vertices and those its collapses add,
// by one index. The vector may grow only while no view is read.
template <class T>
class JoinedView {
 public:
  JoinedView() = default;
  JoinedView(ArrayView<T> base, const std::vector<T>* tail = nullptr) : base_(base), tail_(tail) {}  // NOLINT
  template <class Allocator>
  JoinedView(const std::vector<T, Allocator>& v) : base_(v) {}  // NOLINT: implicit by design

  std::size_t size() const { return base_.size() + (tail_ ? tail_->size() : 0); }
  bool empty() const { return size() == 0; }
  const T& operator[](std::size_t i) const { return i < base_.size() ? base_[i] : (*tail_)[i - base_.size()]; }

 private:
  ArrayView<T> base_;
  const std::vector<T>* tail_ = nullptr;
};

}  // namespace scan2lod
