#include "io/obj_writer.h"

#include "core/error.h"

#include <charconv>
#include <cstdio>
#include <memory>

namespace scan2lod {
namespace {

// Appends numbers and text to a buffer flushed in large blocks: formatting,
// not the disk, is what an ASCII writer spends its time on.
class LineWriter {
 public:
  LineWriter(std::FILE* f) : f_(f) { buffer_.reserve(kBlock + 256); }
  ~LineWriter() { flush(); }
  void text(const char* s) {
    while (*s) buffer_.push_back(*s++);
  }
  void number(float v) {
    char tmp[32];
    const auto r = std::to_chars(tmp, tmp + sizeof tmp, v, std::chars_format::general, 9);
    buffer_.append(tmp, r.ptr);
  }
  void number(long long v) {
    char tmp[24];
    const auto r = std::to_chars(tmp, tmp + sizeof tmp, v);
    buffer_.append(tmp, r.ptr);
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

}  // namespace

void write_obj(const std::string& file, const std::string& name, const TriangleMesh& mesh) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(file.c_str(), "wb"), &std::fclose);
  if (!f) throw InputError(name, "cannot create the file (does the folder exist?)");
  const bool has_n = !mesh.normals.empty(), has_c = !mesh.colors.empty();
  bool failed;
  {
    LineWriter out(f.get());
    out.text("# scan2lod\n");
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
      out.text("v");
      for (int k = 0; k < 3; ++k) out.text(" "), out.number(mesh.positions[i][k]);
      if (has_c)
        for (int k = 0; k < 3; ++k) out.text(" "), out.number(float(mesh.colors[i][k]) / 255.f);
      out.end_line();
    }
    for (std::size_t i = 0; has_n && i < mesh.normals.size(); ++i) {
      out.text("vn");
      for (int k = 0; k < 3; ++k) out.text(" "), out.number(mesh.normals[i][k]);
      out.end_line();
    }
    for (const Triangle& t : mesh.triangles) {
      out.text("f");
      for (int k = 0; k < 3; ++k) {
        out.text(" ");
        out.number((long long)t[k] + 1);
        if (has_n) out.text("//"), out.number((long long)t[k] + 1);
      }
      out.end_line();
    }
    out.flush();
    failed = out.failed();
  }
  if (failed || std::fflush(f.get()) != 0) throw InputError(name, "writing obj failed (disk full?)");
}

}  // namespace scan2lod
