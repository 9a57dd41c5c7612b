// Output for the mesh writers of our own (OBJ, OFF and PLY in double):
// numbers, text or binary records appended to a buffer flushed in large
// blocks, since formatting, not the disk, is what an ASCII writer spends its
// time on, and small writes are what a binary one would.
#pragma once

#include <charconv>
#include <cstdio>
#include <string>

namespace scan2lod {

class LineWriter {
 public:
  explicit LineWriter(std::FILE* f) : f_(f) { buffer_.reserve(kBlock + 256); }
  ~LineWriter() { flush(); }
  void text(const char* s) {
    while (*s) buffer_.push_back(*s++);
  }
  // 9 significant digits: every float reads back exactly.
  void number(float v) {
    char tmp[32];
    const auto r = std::to_chars(tmp, tmp + sizeof tmp, v, std::chars_format::general, 9);
    buffer_.append(tmp, r.ptr);
  }
  // The shortest text that reads back as exactly `v` (at most 17 digits).
  void number(double v) {
    char tmp[32];
    const auto r = std::to_chars(tmp, tmp + sizeof tmp, v);
    buffer_.append(tmp, r.ptr);
  }
  void number(long long v) {
    char tmp[24];
    const auto r = std::to_chars(tmp, tmp + sizeof tmp, v);
    buffer_.append(tmp, r.ptr);
  }
  // The bytes of `value` as they lie in memory (little-endian records).
  template <class T>
  void put(const T& value) {
    buffer_.append(reinterpret_cast<const char*>(&value), sizeof value);
  }
  void end_record() {
    if (buffer_.size() >= kBlock) flush();
  }
  void end_line() {
    buffer_.push_back('\n');
    if (buffer_.size() >= kBlock) flush();
  }
  void flush() {
    if (!buffer_.empty() && std::fwrite(buffer_.data(), 1, buffer_.size(), f_) != buffer_.size()) failed_ = true;
    buffer_.clear();
  }
  bool failed() const { return failed_; }

 private:
  static constexpr std::size_t kBlock = 1 << 20;
  std::FILE* f_;
  std::string buffer_;
  bool failed_ = false;
};

}  // namespace scan2lod
