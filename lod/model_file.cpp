#include <scan2lod/lod/model_file.h>

#include <scan2lod/core/error.h>
#include <scan2lod/io/atomic_file.h>
#include <scan2lod/io/file_extension.h>
#include <scan2lod/lod/clusters/cluster_sections.h>
#include <scan2lod/lod/model_sections.h>
#include <scan2lod/lod/structure.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <system_error>

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>
#include <xxhash.h>

namespace scan2lod {

// The arrays go to disk as they lie in memory; that is the file's byte order
// only on little-endian hosts (every machine this project targets).
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the .mco reader and writer assume a little-endian host");
static_assert(sizeof(Vec3f) == 12 && sizeof(Triangle) == 12 && sizeof(Rgb) == 3,
              "vertex element types must be packed for the .mco layout");

namespace {

constexpr char kMagic[8] = {'S', 'C', 'A', 'N', '2', 'L', 'O', 'D'};
constexpr std::size_t kHeaderBytes = 40;
constexpr std::size_t kEntryBytes = 48;
constexpr std::uint32_t kRequired = 1;

std::string tag_name(std::uint32_t tag) {
  std::string s;
  for (int i = 0; i < 4; ++i) {
    const char c = char((tag >> (8 * i)) & 0xff);
    if (c < 0x20 || c > 0x7e) {
      char hex[16];
      std::snprintf(hex, sizeof hex, "0x%08x", tag);
      return hex;
    }
    s += c;
  }
  return "'" + s + "'";
}

void put_u32(std::uint8_t* p, std::uint32_t v) { std::memcpy(p, &v, 4); }
std::uint32_t get_u32(const std::uint8_t* p) {
  std::uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}

// A tag as a const char*, as structures name their sections.
std::uint32_t tag_code(const char* tag) {
  std::uint32_t code = 0;
  for (int i = 0; i < 4; ++i) code |= std::uint32_t(std::uint8_t(tag[i])) << (8 * i);
  return code;
}

// The shared vertices' sections, written before every structure's (`origin`
// is ORGN's record).
std::vector<SectionRow> vertex_rows(double (&origin)[3]) {
  return {
      {"POSN", true, [](LodModel& m) { return array(m.vertices.positions); }},
      {"NRML", true, [](LodModel& m) { return array(m.vertices.normals); }},
      {"COLR", true, [](LodModel& m) { return array(m.vertices.colors); }},
      // 4.5, optional: older readers give levels about the origin. A model in
      // its inputs' own frame goes without: files stay as they were.
      {"ORGN", false,
       [&origin](LodModel& m) {
         Payload p = record(origin, 24);
         p.written = m.origin != Vec3d::Zero();
         return p;
       },
       kPacked},
  };
}

// One section as the writer lays it out.
struct OutSection {
  std::uint32_t tag;
  std::uint32_t element_size;
  std::uint64_t count;
  const void* data;
  std::uint32_t flags = kRequired;
  std::function<void(const Emit&)> stream;  // Payload::stream
  std::uint64_t stream_checksum = 0;
};

std::uint64_t padded(std::uint64_t n) { return (n + 7) & ~std::uint64_t(7); }

}  // namespace

void put_u64(std::uint8_t* p, std::uint64_t v) { std::memcpy(p, &v, 8); }
std::uint64_t get_u64(const std::uint8_t* p) {
  std::uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}

std::string bytes_text(std::uint64_t n) { return std::to_string(n) + (n == 1 ? " byte" : " bytes"); }

std::uint64_t model_checksum(const void* data, std::size_t size, std::uint64_t seed) {
  return XXH64(data, size, seed);
}

namespace {

// The file's bytes in order, to `out` (called with runs of bytes), with the
// trailer's checksum taken as they pass: a model is written without a copy
// of it in memory.
void emit_model(const LodModel& model, std::uint32_t major,
                const std::function<void(const std::uint8_t*, std::size_t)>& out) {
  if (major < kUnpacked || major > kModelFormatMajor)
    throw std::invalid_argument("encode_model: format " + std::to_string(major) + " is not written");
  // The shared vertices' rows, then each structure's with its records as
  // format `major` lays them out, in the order structures joined the format.
  double origin[3] = {model.origin.x(), model.origin.y(), model.origin.z()};
  std::vector<SectionRow> rows = vertex_rows(origin);
  std::vector<std::unique_ptr<StructureSections>> parts;
  for (const StructureKind* kind : structures_in_file_order()) {
    if (!kind->present(model)) continue;
    parts.push_back(kind->make_sections());
    parts.back()->prepare(model, major);
    for (SectionRow& row : parts.back()->rows()) rows.push_back(std::move(row));
  }
  // The table's payloads are only read here.
  LodModel& readable = const_cast<LodModel&>(model);
  std::vector<OutSection> sections;
  for (const SectionRow& row : rows) {
    if (!row.in(major)) continue;
    Payload p = row.payload(readable);
    if (!p.written) continue;
    sections.push_back({tag_code(row.tag), p.element_size, p.count, p.data, row.required ? kRequired : 0,
                        std::move(p.stream), p.stream_checksum});
  }
  const std::size_t count = sections.size();
  const std::uint64_t directory_end = kHeaderBytes + kEntryBytes * count + 8;
  std::uint64_t length = directory_end;
  for (const OutSection& s : sections) length = padded(length + s.element_size * s.count);
  length += 8;

  std::vector<std::uint8_t> head(directory_end, 0);
  std::uint8_t* header = head.data();
  std::memcpy(header, kMagic, 8);
  put_u32(header + 8, major);
  put_u32(header + 12, major == kModelFormatMajor ? kModelFormatMinor : 0);
  put_u32(header + 16, std::uint32_t(count));
  put_u32(header + 20, 0);
  put_u64(header + 24, length);
  put_u64(header + 32, model_checksum(header, 32));
  std::uint64_t offset = directory_end;
  for (std::size_t i = 0; i < count; ++i) {
    const OutSection& s = sections[i];
    const std::uint64_t size = s.element_size * s.count;
    std::uint8_t* e = head.data() + kHeaderBytes + kEntryBytes * i;
    put_u32(e, s.tag);
    put_u32(e + 4, s.flags);
    put_u32(e + 8, s.element_size);
    put_u32(e + 12, 0);
    put_u64(e + 16, s.count);
    put_u64(e + 24, offset);
    put_u64(e + 32, size);
    put_u64(e + 40, s.stream ? s.stream_checksum : model_checksum(s.data, size));
    offset = padded(offset + size);
  }
  put_u64(head.data() + directory_end - 8, model_checksum(head.data() + kHeaderBytes, kEntryBytes * count));

  std::unique_ptr<XXH64_state_t, XXH_errorcode (*)(XXH64_state_t*)> file(XXH64_createState(), XXH64_freeState);
  if (!file) throw std::bad_alloc();
  XXH64_reset(file.get(), 0);
  auto emit = [&](const std::uint8_t* bytes, std::size_t size) {
    if (size == 0) return;
    XXH64_update(file.get(), bytes, size);
    out(bytes, size);
  };
  emit(head.data(), head.size());
  static const std::uint8_t zeros[8] = {};
  offset = directory_end;
  for (const OutSection& s : sections) {
    const std::uint64_t size = s.element_size * s.count;
    if (s.stream) s.stream(emit);
    else emit(static_cast<const std::uint8_t*>(s.data), size);
    emit(zeros, padded(offset + size) - (offset + size));
    offset = padded(offset + size);
  }
  std::uint8_t trailer[8];
  put_u64(trailer, XXH64_digest(file.get()));
  out(trailer, 8);
}

}  // namespace

std::vector<std::uint8_t> encode_model(const LodModel& model, std::uint32_t major) {
  std::vector<std::uint8_t> bytes;
  emit_model(model, major, [&](const std::uint8_t* p, std::size_t n) { bytes.insert(bytes.end(), p, p + n); });
  return bytes;
}

void check_model_output(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext != ".mco") throw InputError(path, "a model file needs the extension .mco, got '" + ext + "'");
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  std::error_code ec;
  if (!folder.empty() && !std::filesystem::is_directory(folder, ec))
    throw InputError(path, "cannot write: folder " + folder.string() + " does not exist");
}

void save_model(const std::string& path, const LodModel& model) {
  check_model_output(path);
  write_atomically(path, [&](const std::string& tmp) {
    FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw InputError(path, std::string("cannot write: ") + std::strerror(errno));
    bool written = true;
    int error = 0;
    try {
      emit_model(model, kModelFormatMajor, [&](const std::uint8_t* p, std::size_t n) {
        if (written && std::fwrite(p, 1, n, f) != n) written = false, error = errno;
      });
    } catch (...) {
      std::fclose(f);
      throw;
    }
    if (std::fclose(f) != 0 || !written)
      throw InputError(path, std::string("cannot write: ") + std::strerror(written ? errno : error));
  });
}

namespace {

// `path` opened for reading, and its size; InputError when it is missing,
// not a regular file, or unreadable.
int open_model_file(const std::string& path, std::uintmax_t* size) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, "cannot read the model: no such file");
  if (!fs::is_regular_file(path, ec)) throw InputError(path, "cannot read the model: not a regular file");
  *size = fs::file_size(path, ec);
  if (ec) throw InputError(path, "cannot read the model: " + ec.message());
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) throw InputError(path, std::string("cannot read the model: ") + std::strerror(errno));
  return fd;
}

}  // namespace

LodModel load_model(const std::string& path) {
  std::uintmax_t size = 0;
  const int fd = open_model_file(path, &size);
  // Mapped rather than read into a buffer: the decoder copies each section
  // once, straight from the page cache.
  void* mapped = size ? ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0) : MAP_FAILED;
  if (mapped != MAP_FAILED) {
    ::close(fd);
    const std::unique_ptr<void, std::function<void(void*)>> unmap(mapped, [size](void* p) { ::munmap(p, size); });
    return decode_model(static_cast<const std::uint8_t*>(mapped), size, path);
  }
  // Not mappable (or empty): read it whole. Not zeroed first: every byte is read over.
  const std::unique_ptr<std::uint8_t[]> bytes(new std::uint8_t[std::max<std::uintmax_t>(size, 1)]);
  std::size_t got = 0;
  while (got < size) {
    const ssize_t r = ::read(fd, bytes.get() + got, size - got);
    if (r <= 0) break;
    got += std::size_t(r);
  }
  ::close(fd);
  if (got != size)
    throw InputError(path, "cannot read the model: read " + std::to_string(got) + " of " + std::to_string(size) + " bytes");
  return decode_model(bytes.get(), size, path);
}

namespace {

// Reads one model from bytes, phase by phase: the header, the directory, the
// checksums, the shared vertices, then each registered structure's part
// (lod/model_sections.h), which checks that its contents agree, so that
// extraction cannot read out of bounds on what it returns.
class Decoder final : public SectionReader {
 public:
  Decoder(const std::uint8_t* data, std::size_t size, const std::string& source)
      : data_(data), size_(size), source_(source) {}
  // Paged: reads from `fd` (a file of `size` bytes) only the header, the
  // directory and the sections it decodes, checking each one's checksum.
  Decoder(int fd, std::size_t size, const std::string& source) : data_(nullptr), size_(size), source_(source), fd_(fd) {}

  LodModel decode();
  ModelPagesHead decode_pages_head();

  std::uint32_t major() const override { return major_; }
  bool has(const char* tag) const override { return by_tag_.count(tag_code(tag)) > 0; }
  const FileSection& section(const char* tag) const override;
  const std::uint8_t* payload(const FileSection& s) override;
  void read_rows(const std::vector<SectionRow>& rows, LodModel* model) override;
  std::size_t vertices() const override { return vertices_; }
  bool paged() const override { return fd_ >= 0; }
  const std::string& source() const override { return source_; }

 private:
  void read_header();
  void read_directory();
  void verify_length_and_checksums() const;
  void index_sections();
  void read_origin(LodModel* model);
  void check_vertices(const LodModel& model) const;
  void read_head();

  const std::uint8_t* data_;
  std::size_t size_;
  const std::string& source_;
  int fd_ = -1;                                  // paged: the file, read a section at a time
  std::vector<std::uint8_t> head_;               // paged: the header and directory
  std::vector<std::vector<std::uint8_t>> held_;  // paged: the sections read
  std::uint64_t bytes_read_ = 0;                 // paged
  std::uint32_t major_ = 0, minor_ = 0;
  std::string format_;
  std::uint64_t file_length_ = 0, directory_end_ = 0;
  std::vector<FileSection> sections_;
  std::map<std::uint32_t, const FileSection*> by_tag_;
  std::size_t vertices_ = 0;
};

// Header: what the file is, before anything is trusted.
void Decoder::read_header() {
  if (size_ == 0) fail("not a scan2lod model (.mco): the file is empty");
  if (std::memcmp(data_, kMagic, std::min<std::size_t>(size_, 8)) != 0)
    fail("not a scan2lod model (.mco): bad magic, the file does not start with \"SCAN2LOD\"");
  if (size_ < kHeaderBytes) fail("truncated in the header: " + bytes_text(size_) + " of " + std::to_string(kHeaderBytes));
  if (model_checksum(data_, 32) != get_u64(data_ + 32)) fail("checksum mismatch in the header (damaged file)");
  major_ = get_u32(data_ + 8);
  minor_ = get_u32(data_ + 12);
  if (major_ > kModelFormatMajor)
    fail("written by a newer scan2lod (format " + std::to_string(major_) + "." + std::to_string(minor_) +
         ", this reads up to " + std::to_string(kModelFormatMajor) + ")");
  if (major_ == 0) fail("format version 0 was never written by scan2lod");
  if (major_ < 2)
    fail("written by an older scan2lod (format " + std::to_string(major_) + "." + std::to_string(minor_) +
         "), whose crack patching triangulated differently from this one's; rebuild the model with scan2lod build");
  format_ = "format " + std::to_string(major_) + "." + std::to_string(minor_);
  const std::uint64_t section_count = get_u32(data_ + 16);
  file_length_ = get_u64(data_ + 24);
  directory_end_ = kHeaderBytes + kEntryBytes * section_count + 8;
  if (file_length_ < directory_end_ + 8)
    fail("the header's file length " + std::to_string(file_length_) + " cannot hold " +
         std::to_string(section_count) + " sections");
}

// Directory: where each section lies; all of it inside the stated length.
void Decoder::read_directory() {
  const std::uint64_t section_count = get_u32(data_ + 16);
  if (size_ < directory_end_)
    fail("truncated in the section directory: " + bytes_text(size_) + " of " + std::to_string(file_length_));
  if (model_checksum(data_ + kHeaderBytes, kEntryBytes * section_count) != get_u64(data_ + directory_end_ - 8))
    fail("checksum mismatch in the section directory (damaged file)");
  sections_.resize(section_count);
  for (std::size_t i = 0; i < section_count; ++i) {
    const std::uint8_t* e = data_ + kHeaderBytes + kEntryBytes * i;
    FileSection& s = sections_[i];
    s = {get_u32(e), get_u32(e + 4), get_u32(e + 8), get_u64(e + 16), get_u64(e + 24), get_u64(e + 32), get_u64(e + 40)};
    const std::string name = "section " + tag_name(s.tag);
    if (s.element_size == 0 || s.count > std::numeric_limits<std::uint64_t>::max() / s.element_size ||
        s.count * s.element_size != s.length)
      fail(name + ": " + std::to_string(s.count) + " elements of " + bytes_text(s.element_size) + " do not make its " +
           bytes_text(s.length));
    if (s.offset < directory_end_ || s.offset > file_length_ - 8 || s.length > file_length_ - 8 - s.offset)
      fail(name + ": its " + bytes_text(s.length) + " at offset " + std::to_string(s.offset) +
           " lie outside the model's " + bytes_text(file_length_));
  }
}

// Length: a short file is truncated somewhere; say where. Then every checksum.
void Decoder::verify_length_and_checksums() const {
  if (size_ < file_length_) {
    const FileSection* cut = nullptr;
    for (const FileSection& s : sections_)
      if (s.offset + s.length > size_ && (!cut || s.offset < cut->offset)) cut = &s;
    fail("truncated in " + (cut ? "section " + tag_name(cut->tag) : std::string("the trailing checksum")) + ": " +
         bytes_text(size_) + " of " + std::to_string(file_length_));
  }
  if (size_ > file_length_)
    fail(bytes_text(size_ - file_length_) + " after the end of the model (" + bytes_text(file_length_) + ")");
  if (fd_ >= 0) return;  // paged: each section is checked as it is read
  for (const FileSection& s : sections_)
    if (model_checksum(data_ + s.offset, s.length) != s.checksum)
      fail("checksum mismatch in section " + tag_name(s.tag) + " (damaged file)");
  if (model_checksum(data_, file_length_ - 8) != get_u64(data_ + file_length_ - 8))
    fail("checksum mismatch over the whole file (damaged padding)");
}

// Sections by tag: each known one once; unknown ones only if optional.
void Decoder::index_sections() {
  for (const FileSection& s : sections_)
    if (!by_tag_.emplace(s.tag, &s).second) fail("section " + tag_name(s.tag) + " appears twice");
  // Every tag the format knows: the shared vertices' and every structure's.
  double origin[3];
  std::vector<std::uint32_t> known_tags;
  for (const SectionRow& row : vertex_rows(origin)) known_tags.push_back(tag_code(row.tag));
  for (const StructureKind* kind : registered_structures())
    for (const SectionRow& row : kind->make_sections()->rows()) known_tags.push_back(tag_code(row.tag));
  for (const FileSection& s : sections_) {
    const bool known = std::any_of(known_tags.begin(), known_tags.end(), [&](std::uint32_t t) { return t == s.tag; });
    if ((s.flags & kRequired) && !known)
      fail("needs section " + tag_name(s.tag) + ", which this scan2lod does not know (" + format_ + ", this reads " +
           std::to_string(kModelFormatMajor) + "." + std::to_string(kModelFormatMinor) + "): written by a newer scan2lod");
  }
}

const FileSection& Decoder::section(const char* tag) const {
  auto it = by_tag_.find(tag_code(tag));
  if (it == by_tag_.end()) throw InputError(source_, "missing section '" + std::string(tag) + "'");
  return *it->second;
}

// The arrays of `rows`, as a structure's part lists them (records are read by
// their own functions, which check their sizes).
void Decoder::read_rows(const std::vector<SectionRow>& rows, LodModel* model) {
  for (const SectionRow& row : rows) {
    if (!row.in(major_)) continue;
    const Payload p = row.payload(*model);
    if (!p.resize || (!row.required && !has(row.tag))) continue;
    const FileSection& s = section(row.tag);
    if (s.element_size != p.element_size)
      fail("section '" + std::string(row.tag) + "' has elements of " + bytes_text(s.element_size) + ", expected " +
           std::to_string(p.element_size));
    if (p.left_in_file) continue;
    void* into = p.resize(p.vector, s.count);  // s.length bytes, inside the file: bounded by its size
    if (s.length) std::memcpy(into, payload(s), s.length);
  }
}

// Optional (added in 4.5): without it the vertices are in the inputs' frame.
void Decoder::read_origin(LodModel* model) {
  if (!has("ORGN")) return;
  const FileSection& s = section("ORGN");
  if (s.count != 1 || s.element_size != 24) bad("section 'ORGN' must be one record of 24 bytes");
  const std::uint8_t* origin = payload(s);
  for (int i = 0; i < 3; ++i) std::memcpy(&model->origin[i], origin + 8 * i, 8);
  if (!model->origin.allFinite()) bad("section 'ORGN': the origin must be a finite point");
}

void Decoder::check_vertices(const LodModel& model) const {
  const std::size_t vertices = model.vertices.size();
  if (vertices > kMaxIndex) bad(std::to_string(vertices) + " vertices, more than 32-bit indices address");
  if (!model.vertices.normals.empty() && model.vertices.normals.size() != vertices)
    bad(std::to_string(model.vertices.normals.size()) + " normals for " + std::to_string(vertices) + " vertices");
  if (!model.vertices.colors.empty() && model.vertices.colors.size() != vertices)
    bad(std::to_string(model.vertices.colors.size()) + " colours for " + std::to_string(vertices) + " vertices");
}

// Paged: `n` bytes from `offset` of the file; false when the file is shorter.
bool read_at(int fd, std::uint64_t offset, std::size_t n, std::uint8_t* into) {
  while (n > 0) {
    const ssize_t r = ::pread(fd, into, n, off_t(offset));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return false;
    into += r, offset += std::uint64_t(r), n -= std::size_t(r);
  }
  return true;
}

// A section's bytes: in the file's bytes, or (paged) read and checked now.
const std::uint8_t* Decoder::payload(const FileSection& s) {
  if (fd_ < 0) return data_ + s.offset;
  held_.emplace_back(std::max<std::uint64_t>(s.length, 1));
  if (!read_at(fd_, s.offset, s.length, held_.back().data()))
    fail("cannot read section " + tag_name(s.tag) + ": " + std::strerror(errno ? errno : EIO));
  bytes_read_ += s.length;
  if (model_checksum(held_.back().data(), s.length) != s.checksum)
    fail("checksum mismatch in section " + tag_name(s.tag) + " (damaged file)");
  return held_.back().data();
}

// Paged: the header, then the directory it sizes.
void Decoder::read_head() {
  head_.resize(std::min<std::size_t>(size_, kHeaderBytes));
  if (!read_at(fd_, 0, head_.size(), head_.data())) fail("cannot read the header");
  data_ = head_.data();
  read_header();
  head_.resize(std::min<std::uint64_t>(size_, directory_end_));
  if (!read_at(fd_, 0, head_.size(), head_.data())) fail("cannot read the section directory");
  data_ = head_.data();
  bytes_read_ += head_.size();
}

ModelPagesHead Decoder::decode_pages_head() {
  read_head();
  read_directory();
  verify_length_and_checksums();
  index_sections();
  ModelPagesHead head;
  if (major_ < kPacked || !has("CINF") || !has("PGIX") || !has("PGEO") || !has("PAGE")) return head;
  LodModel& model = head.model;
  read_origin(&model);
  vertices_ = section("POSN").count;
  head.normals = section("NRML").count > 0;
  head.colors = section("COLR").count > 0;
  if (vertices_ > kMaxIndex) bad(std::to_string(vertices_) + " vertices, more than 32-bit indices address");
  if ((head.normals && section("NRML").count != vertices_) || (head.colors && section("COLR").count != vertices_))
    bad("normals or colours do not match the " + std::to_string(vertices_) + " vertices");
  ClusterSections clusters;
  clusters.decode(*this, &model);
  clusters.check_page_extents(*this, *model.clusters);
  head.extents = std::move(clusters.page_extents());
  head.pages_offset = section("PGEO").offset;
  head.vertices = vertices_;
  head.bytes_read = bytes_read_;
  return head;
}

LodModel Decoder::decode() {
  read_header();
  read_directory();
  verify_length_and_checksums();
  index_sections();
  LodModel model;
  double origin[3];
  read_rows(vertex_rows(origin), &model);
  read_origin(&model);
  vertices_ = model.vertices.size();
  check_vertices(model);
  bool any = false;
  for (const StructureKind* kind : registered_structures()) {
    const std::unique_ptr<StructureSections> part = kind->make_sections();
    if (part->in(*this)) part->decode(*this, &model), any = true;
  }
  if (!any) {
    std::string marks;
    for (const StructureKind* kind : structures_in_file_order())
      marks += (marks.empty() ? "neither " : " nor ") + kind->make_sections()->mark();
    fail("holds no LOD structure: " + marks);
  }
  return model;
}

}  // namespace

LodModel decode_model(const std::uint8_t* data, std::size_t size, const std::string& source) {
  return Decoder(data, size, source).decode();
}

ModelPagesHead read_model_pages_head(const std::string& path) {
  std::uintmax_t size = 0;
  const int fd = open_model_file(path, &size);
  const std::unique_ptr<int, void (*)(int*)> closing(new int(fd), [](int* f) { ::close(*f), delete f; });
  return Decoder(fd, std::size_t(size), path).decode_pages_head();
}

}  // namespace scan2lod
