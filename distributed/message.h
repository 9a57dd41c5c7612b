// Plain values to bytes and back, for what the ranks of a job send each
// other (work_sharing.h). Both ends run the same binary on the same kind of
// machine, so values travel as they lie in memory; a reader that runs past
// the end throws instead of reading garbage.
#pragma once

#include <scan2lod/core/types.h>

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace scan2lod {

// What travels as it lies in memory: trivially copyable values, and the
// plain-float vectors of core/types.h (Eigen's, which the standard's rule
// does not count). A struct of those may say so by specializing this.
template <class T>
struct TravelsAsBytes : std::is_trivially_copyable<T> {};
template <>
struct TravelsAsBytes<Vec3f> : std::true_type {};

class MessageWriter {
 public:
  template <class T>
  void put(const T& value) {
    static_assert(TravelsAsBytes<T>::value, "values travel as they lie in memory");
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  template <class T>
  void put(const std::vector<T>& values) {
    static_assert(TravelsAsBytes<T>::value, "values travel as they lie in memory");
    put(std::uint64_t(values.size()));
    bytes_.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
  }
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
};

class MessageReader {
 public:
  explicit MessageReader(const std::string& bytes) : bytes_(bytes) {}
  template <class T>
  void get(T* value) {
    static_assert(TravelsAsBytes<T>::value, "values travel as they lie in memory");
    std::memcpy(static_cast<void*>(value), take(sizeof(T)), sizeof(T));
  }
  template <class T>
  void get(std::vector<T>* values) {
    static_assert(TravelsAsBytes<T>::value, "values travel as they lie in memory");
    std::uint64_t n = 0;
    get(&n);
    if (n > (bytes_.size() - at_) / sizeof(T)) throw std::runtime_error("a message between ranks is cut short");
    values->resize(n);
    if (n > 0) std::memcpy(static_cast<void*>(values->data()), take(n * sizeof(T)), n * sizeof(T));
  }
  bool done() const { return at_ == bytes_.size(); }

 private:
  const char* take(std::size_t n) {
    if (n > bytes_.size() - at_) throw std::runtime_error("a message between ranks is cut short");
    const char* p = bytes_.data() + at_;
    at_ += n;
    return p;
  }
  const std::string& bytes_;
  std::size_t at_ = 0;
};

}  // namespace scan2lod
