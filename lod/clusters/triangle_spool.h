// Triangles kept on disk while a build runs: the cluster hierarchy built in
// blocks appends each finished cluster's triangles here, so that none of
// them takes memory until the model is written, and the model's 'CTRI'
// section is then copied from the file in runs. A spool is a scratch file of
// one build, not a format: it is removed with the object.
#pragma once

#include <scan2lod/core/types.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace scan2lod {

class TriangleSpool {
 public:
  // Creates (or truncates) the file at `path`. Throws InputError naming it
  // when it cannot be created.
  explicit TriangleSpool(std::string path);
  ~TriangleSpool();
  TriangleSpool(const TriangleSpool&) = delete;
  TriangleSpool& operator=(const TriangleSpool&) = delete;

  // Appends `count` triangles. Throws InputError naming the file when the
  // disk refuses them (full, or gone).
  void append(const Triangle* triangles, std::size_t count);
  std::uint64_t size() const { return count_; }  // triangles appended
  const std::string& path() const { return path_; }

  // XXH64 (seed 0) of the bytes appended: the model's section checksum.
  std::uint64_t checksum() const;
  // Calls out(bytes, n) over the spooled bytes in order, a run at a time.
  void read(const std::function<void(const std::uint8_t*, std::size_t)>& out) const;
  // Everything back in memory.
  std::vector<Triangle> load() const;

 private:
  void flush() const;

  std::string path_;
  int fd_ = -1;
  std::uint64_t count_ = 0;
  mutable std::vector<Triangle> buffer_;  // appended, not yet written
  struct Hash;
  std::unique_ptr<Hash> hash_;
};

}  // namespace scan2lod
