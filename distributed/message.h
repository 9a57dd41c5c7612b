// Plain values to bytes and back, for what the ranks of a job send each
// other (work_sharing.h). Both ends run the same binary on the same kind of
// machine, so values travel as they lie in memory; a reader that runs past
// the end throws instead of reading garbage.
#pragma once

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace scan2lod {

class MessageWriter {
 public:
  template <class T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>, "values travel as they lie in memory");
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  template <class T>
  void put(const std::vector<T>& values) {
    static_assert(std::is_trivially_copyable_v<T>, "values travel as they lie in memory");
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
    static_assert(std::is_trivially_copyable_v<T>, "values travel as they lie in memory");
    std::memcpy(value, take(sizeof(T)), sizeof(T));
  }
  template <class T>
  void get(std::vector<T>* values) {
    static_assert(std::is_trivially_copyable_v<T>, "values travel as they lie in memory");
    std::uint64_t n = 0;
    get(&n);
    if (n > (bytes_.size() - at_) / sizeof(T)) throw std::runtime_error("a message between ranks is cut short");
    values->resize(n);
    if (n > 0) std::memcpy(values->data(), take(n * sizeof(T)), n * sizeof(T));
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
