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
// by one index. The vector may grow only while no view is read, or, for a
// frozen view, within its capacity (the view keeps the size it had).
template <class T>
class JoinedView {
 public:
  JoinedView() = default;
  JoinedView(ArrayView<T> base, const std::vector<T>* tail = nullptr) : base_(base), tail_(tail) {}  // NOLINT
  template <class Allocator>
  JoinedView(const std::vector<T, Allocator>& v) : base_(v) {}  // NOLINT: implicit by design

  std::size_t size() const { return base_.size() + (!tail_ ? 0 : frozen_ ? tail_size_ : tail_->size()); }
  bool empty() const { return size() == 0; }
  const T& operator[](std::size_t i) const { return i < base_.size() ? base_[i] : tail_->data()[i - base_.size()]; }
  // This view as it is now, for threads that read it while another appends
  // to the vector within its capacity: it never reads the vector's size.
  JoinedView frozen() const {
    JoinedView v = *this;
    v.frozen_ = true;
    v.tail_size_ = tail_ ? tail_->size() : 0;
    return v;
  }

 private:
  ArrayView<T> base_;
  const std::vector<T>* tail_ = nullptr;
  bool frozen_ = false;
  std::size_t tail_size_ = 0;
};

}  // namespace scan2lod
