// A structure's part of the model file (lod/model_file.h): its sections as
// rows the writer and the reader both walk, the records they hold besides the
// model's arrays, and its decoding with the checks that keep extraction in
// bounds. lod/model_file.cpp keeps the header, directory, checksums and shared
// vertices, and calls each registered structure's part (lod/structure.h).
// Internal to the library.
#pragma once

#include <scan2lod/core/error.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/lod/octree/model_pack.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace scan2lod {

constexpr std::uint32_t kUnpacked = 3;  // the last format that stored the octree's arrays whole
constexpr std::uint32_t kPacked = 4;    // the first that packs them

constexpr std::size_t kMaxIndex = std::size_t(std::numeric_limits<std::int32_t>::max());

// Runs of a payload's bytes, as the writer hands them on.
using Emit = std::function<void(const std::uint8_t*, std::size_t)>;

// A section's payload in memory: element size, count and bytes, and for an
// array how to size it before reading into it.
struct Payload {
  std::uint32_t element_size = 0;
  std::uint64_t count = 0;
  void* data = nullptr;
  void* (*resize)(void* vector, std::uint64_t count) = nullptr;  // null for a record
  void* vector = nullptr;
  // Writer: false leaves the section out of this file.
  bool written = true;
  // Writer: the payload when it is not in memory (a spool, or pages encoded
  // as they are written), with its checksum taken beforehand.
  std::function<void(const Emit&)> stream;
  std::uint64_t stream_checksum = 0;
  // Reader: checked but left in the file (a paged reader's triangles).
  bool left_in_file = false;
};

template <class T, class Allocator>
Payload array(std::vector<T, Allocator>& v) {
  Payload p;
  p.element_size = std::uint32_t(sizeof(T));
  p.count = v.size();
  p.data = static_cast<void*>(v.data());
  p.resize = [](void* vector, std::uint64_t count) -> void* {
    auto& v = *static_cast<std::vector<T, Allocator>*>(vector);
    resize_for_load(&v, count);
    return static_cast<void*>(v.data());
  };
  p.vector = &v;
  return p;
}

template <class T>
Payload record(T* r, std::size_t bytes) {
  Payload p;
  p.element_size = std::uint32_t(bytes);
  p.count = 1;
  p.data = static_cast<void*>(r);
  return p;
}

// A section written from a stream and never read into memory by load_model.
inline Payload streamed(std::uint64_t bytes) {
  Payload p;
  p.element_size = 1;
  p.count = bytes;
  return p;
}

// One section the format knows: its tag, whether a reader must know it
// (flags bit 0), its payload over a model, and the formats that hold it.
struct SectionRow {
  char tag[5];
  bool required;
  std::function<Payload(LodModel& model)> payload;
  std::uint32_t first_major = 2, last_major = kModelFormatMajor;

  bool in(std::uint32_t major) const { return major >= first_major && major <= last_major; }
};

// One directory entry as read.
struct FileSection {
  std::uint32_t tag, flags, element_size;
  std::uint64_t count, offset, length, checksum;
};

// The file as a structure's part reads it: sections by tag, their bytes
// (checked against their checksums), and failures naming the file.
class SectionReader {
 public:
  virtual ~SectionReader() = default;
  virtual std::uint32_t major() const = 0;
  virtual bool has(const char* tag) const = 0;
  // Throws InputError "missing section" when the file has no such section.
  virtual const FileSection& section(const char* tag) const = 0;
  virtual const std::uint8_t* payload(const FileSection& s) = 0;
  // Reads the arrays of `rows` in this file's format into `model` (records
  // are read by the part itself, which checks their sizes); optional ones the
  // file lacks are left as they are.
  virtual void read_rows(const std::vector<SectionRow>& rows, LodModel* model) = 0;
  // The shared vertices' count, which indices must stay below.
  virtual std::size_t vertices() const = 0;
  // Reading section by section from a file (lod/clusters/paged_model.h)
  // rather than from its bytes in memory.
  virtual bool paged() const = 0;
  virtual const std::string& source() const = 0;
  [[noreturn]] void fail(const std::string& what) const { throw InputError(source(), what); }
  [[noreturn]] void bad(const std::string& what) const { fail("inconsistent model: " + what); }
};

// One structure's part of one model file being written or read, holding the
// records its sections hold besides the model's arrays.
class StructureSections {
 public:
  virtual ~StructureSections() = default;
  // Every section of the structure, in the order the writer lays them out;
  // the payloads point into the model and into this part's records.
  virtual std::vector<SectionRow> rows() = 0;
  // Writer: the records of `model` (which must hold the structure) as format
  // `major` lays them out, before rows() is read. `model` must outlive the
  // writing.
  virtual void prepare(const LodModel& model, std::uint32_t major) = 0;
  // Reader: whether the file holds the structure, and how that shows (for a
  // file that holds none: "an octree ('GRID')").
  virtual bool in(const SectionReader& file) const = 0;
  virtual std::string mark() const = 0;
  // Reader: the structure from `file` into `model`, checked so that no level
  // can read out of bounds. Throws InputError through file.fail() or bad().
  virtual void decode(SectionReader& file, LodModel* model) = 0;
};

std::string bytes_text(std::uint64_t n);
void put_u64(std::uint8_t* p, std::uint64_t v);
std::uint64_t get_u64(const std::uint8_t* p);

}  // namespace scan2lod
