#include <scan2lod/io/mesh_file.h>

#include <scan2lod/core/error.h>
#include <scan2lod/io/atomic_file.h>
#include <scan2lod/io/double_positions.h>
#include <scan2lod/io/file_extension.h>
#include <scan2lod/io/gltf_file.h>
#include <scan2lod/io/gltf_read.h>
#include <scan2lod/io/local_origin.h>
#include <scan2lod/io/obj_writer.h>
#include <scan2lod/io/ply_header.h>
#include <scan2lod/io/used_vertices.h>
#include <scan2lod/io/vtp_file.h>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/exporter/BaseExporter.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/IO/reader/OFFReader.hh>
#include <OpenMesh/Core/IO/reader/PLYReader.hh>
#include <OpenMesh/Core/IO/reader/STLReader.hh>
#include <OpenMesh/Core/IO/writer/OFFWriter.hh>
#include <OpenMesh/Core/IO/writer/PLYWriter.hh>
#include <OpenMesh/Core/IO/writer/STLWriter.hh>
#include <OpenMesh/Core/Mesh/BaseKernel.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <charconv>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <optional>
#include <sstream>
#include <string_view>
#include <system_error>

namespace scan2lod {
namespace {

namespace fs = std::filesystem;
namespace omio = OpenMesh::IO;

static_assert(sizeof(Vec3f) == 3 * sizeof(float), "Vec3f must be packed for bulk copies");

// OpenMesh's readers and writers are singletons with per-file state.
std::mutex& openmesh_io_mutex() {
  static std::mutex m;
  return m;
}

std::uintmax_t file_size_or_zero(const std::string& path) {
  std::error_code ec;
  std::uintmax_t size = fs::file_size(path, ec);
  return ec ? 0 : size;
}

// OpenMesh prints its own diagnostics; ours name the file and what was expected.
class QuietOpenMesh {
 public:
  QuietOpenMesh()
      : err_(omerr().is_enabled()), log_(omlog().is_enabled()), out_(omout().is_enabled()) {
    omerr().disable();
    omlog().disable();
    omout().disable();
  }
  ~QuietOpenMesh() {
    if (err_) omerr().enable();
    if (log_) omlog().enable();
    if (out_) omout().enable();
  }

 private:
  bool err_, log_, out_;
};

// ---------------------------------------------------------------------------
// Reading: an importer that appends straight into flat arrays.

class FlatImporter : public omio::BaseImporter {
 public:
  explicit FlatImporter(std::size_t reserve_cap) : reserve_cap_(reserve_cap) {}

  std::vector<Vec3f> positions, normals;
  std::vector<Rgb> colors;
  std::vector<Triangle> triangles;
  bool saw_normal = false, saw_color = false;
  std::size_t faces_seen = 0;
  // First face that could not be used, for the error message.
  std::size_t bad_face = SIZE_MAX;
  std::string bad_face_why;

  OpenMesh::VertexHandle add_vertex(const OpenMesh::Vec3f& p) override {
    positions.emplace_back(p[0], p[1], p[2]);
    normals.emplace_back(Vec3f::Zero());
    colors.push_back(Rgb{0, 0, 0});
    return OpenMesh::VertexHandle(int(positions.size() - 1));
  }
  OpenMesh::VertexHandle add_vertex() override { return add_vertex(OpenMesh::Vec3f(0, 0, 0)); }

  OpenMesh::FaceHandle add_face(const VHandles& corners) override {
    std::size_t face = faces_seen++;
    if (corners.size() < 3) return reject(face, "has fewer than 3 corners");
    for (const auto& vh : corners)
      if (vh.idx() < 0 || std::size_t(vh.idx()) >= positions.size())
        return reject(face, "names vertex " + std::to_string(unsigned(vh.idx())) +
                                " but only " + std::to_string(positions.size()) +
                                " vertices precede it");
    // Fan triangulation keeps the polygon's winding.
    for (std::size_t i = 1; i + 1 < corners.size(); ++i)
      triangles.push_back({corners[0].idx(), corners[i].idx(), corners[i + 1].idx()});
    return OpenMesh::FaceHandle(int(face));
  }

  void set_point(OpenMesh::VertexHandle vh, const OpenMesh::Vec3f& p) override {
    if (valid(vh)) positions[vh.idx()] = Vec3f(p[0], p[1], p[2]);
  }
  void set_normal(OpenMesh::VertexHandle vh, const OpenMesh::Vec3f& n) override {
    if (!valid(vh)) return;
    normals[vh.idx()] = Vec3f(n[0], n[1], n[2]);
    saw_normal = true;
  }
  void set_normal(OpenMesh::VertexHandle vh, const OpenMesh::Vec3d& n) override {
    set_normal(vh, OpenMesh::Vec3f(float(n[0]), float(n[1]), float(n[2])));
  }
  void set_color(OpenMesh::VertexHandle vh, const OpenMesh::Vec3uc& c) override {
    if (!valid(vh)) return;
    colors[vh.idx()] = Rgb{c[0], c[1], c[2]};
    saw_color = true;
  }
  void set_color(OpenMesh::VertexHandle vh, const OpenMesh::Vec4uc& c) override {
    set_color(vh, OpenMesh::Vec3uc(c[0], c[1], c[2]));
  }
  void set_color(OpenMesh::VertexHandle vh, const OpenMesh::Vec3f& c) override {
    set_color(vh, OpenMesh::Vec3uc(to_byte(c[0]), to_byte(c[1]), to_byte(c[2])));
  }
  void set_color(OpenMesh::VertexHandle vh, const OpenMesh::Vec4f& c) override {
    set_color(vh, OpenMesh::Vec3uc(to_byte(c[0]), to_byte(c[1]), to_byte(c[2])));
  }

  void reserve(unsigned int nv, unsigned int, unsigned int nf) override {
    // Counts come from the file; a garbled header must not allocate gigabytes.
    positions.reserve(std::min<std::size_t>(nv, reserve_cap_));
    normals.reserve(std::min<std::size_t>(nv, reserve_cap_));
    colors.reserve(std::min<std::size_t>(nv, reserve_cap_));
    triangles.reserve(std::min<std::size_t>(nf, reserve_cap_));
  }
  size_t n_vertices() const override { return positions.size(); }
  size_t n_faces() const override { return faces_seen; }
  size_t n_edges() const override { return 0; }

  // Attributes this project does not carry.
  OpenMesh::HalfedgeHandle add_edge(OpenMesh::VertexHandle, OpenMesh::VertexHandle) override {
    return OpenMesh::HalfedgeHandle();
  }
  OpenMesh::FaceHandle add_face(OpenMesh::HalfedgeHandle) override {
    return OpenMesh::FaceHandle();
  }
  void add_face_texcoords(OpenMesh::FaceHandle, OpenMesh::VertexHandle,
                          const std::vector<OpenMesh::Vec2f>&) override {}
  void add_face_texcoords(OpenMesh::FaceHandle, OpenMesh::VertexHandle,
                          const std::vector<OpenMesh::Vec3f>&) override {}
  void set_face_texindex(OpenMesh::FaceHandle, int) override {}
  void set_halfedge(OpenMesh::VertexHandle, OpenMesh::HalfedgeHandle) override {}
  void set_texcoord(OpenMesh::VertexHandle, const OpenMesh::Vec2f&) override {}
  void set_texcoord(OpenMesh::HalfedgeHandle, const OpenMesh::Vec2f&) override {}
  void set_texcoord(OpenMesh::VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_texcoord(OpenMesh::HalfedgeHandle, const OpenMesh::Vec3f&) override {}
  void set_status(OpenMesh::VertexHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_status(OpenMesh::HalfedgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_status(OpenMesh::EdgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_status(OpenMesh::FaceHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_next(OpenMesh::HalfedgeHandle, OpenMesh::HalfedgeHandle) override {}
  void set_face(OpenMesh::HalfedgeHandle, OpenMesh::FaceHandle) override {}
  void request_face_texcoords2D() override {}
  void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec3f&) override {}
  void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec4f&) override {}
  void set_normal(OpenMesh::FaceHandle, const OpenMesh::Vec3f&) override {}
  void set_normal(OpenMesh::FaceHandle, const OpenMesh::Vec3d&) override {}
  void set_color(OpenMesh::FaceHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(OpenMesh::FaceHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(OpenMesh::FaceHandle, const OpenMesh::Vec3f&) override {}
  void set_color(OpenMesh::FaceHandle, const OpenMesh::Vec4f&) override {}
  void add_texture_information(int, std::string) override {}

 private:
  bool valid(OpenMesh::VertexHandle vh) const {
    return vh.idx() >= 0 && std::size_t(vh.idx()) < positions.size();
  }
  static unsigned char to_byte(float v) {
    return (unsigned char)std::lround(std::clamp(v, 0.f, 1.f) * 255.f);
  }
  OpenMesh::FaceHandle reject(std::size_t face, const std::string& why) {
    if (bad_face == SIZE_MAX) {
      bad_face = face;
      bad_face_why = why;
    }
    return OpenMesh::FaceHandle();
  }
  std::size_t reserve_cap_;
};

// What a mesh file's header promises; the reader must deliver exactly that.
struct ExpectedCounts {
  bool known = false;
  std::size_t vertices = 0, faces = 0;
};

// A header that runs longer is taken for one without end_header.
constexpr std::size_t kOpenMeshHeaderLines = 99999;

// A header line as messages show it: without trailing '\r' and blanks.
std::string trimmed(std::string line) {
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
  return line;
}

// OpenMesh reads the header as a stream of words, not lines: its format is
// the 2nd to 4th word, and a keyword anywhere (say after the version or in
// an obj_info line) starts a new entry, e.g. a property before any element,
// which it appends to an element that does not exist (a crash). So every
// line must have exactly the words its keyword takes. `element_seen`: an
// element line came before.
void check_openmesh_words(const std::string& path, const PlyHeaderLine& header_line, bool* element_seen) {
  const std::string line = trimmed(header_line.text);
  const std::vector<std::string>& words = header_line.words;
  const std::string key = words.empty() ? std::string() : words[0];
  const std::size_t n = header_line.number;
  const std::string where = "PLY header line " + std::to_string(n);
  const std::size_t word_count = words.size();
  bool has_keyword = false;
  for (std::size_t i = 1; i < word_count; ++i)
    has_keyword |= words[i] == "format" || words[i] == "element" || words[i] == "property" ||
                   words[i] == "end_header" || words[i] == "comment";
  auto expect_words = [&](std::size_t count, const char* form) {
    if (word_count != count)
      throw InputError(path, where + ": expected '" + form + "', got '" + line + "'");
  };
  if ((n == 2) != (key == "format"))
    throw InputError(path, where + ": expected the format line right after 'ply', and only there");
  if (key == "obj_info" && has_keyword)
    throw InputError(path, where + ": obj_info holds a PLY keyword, which OpenMesh would read as one");
  if (key == "format") {
    expect_words(3, "format FORMAT 1.0");
    const std::string& format = words[1];
    const std::string& version = words[2];
    char* end = nullptr;
    std::strtod(version.c_str(), &end);
    if (end != version.c_str() + version.size())
      throw InputError(path, where + ": version '" + version + "' is not a number");
    if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
      throw InputError(path, where + ": unknown format '" + format +
                                 "', expected ascii, binary_little_endian or binary_big_endian");
  } else if (key == "element") {
    expect_words(3, "element NAME COUNT");
    long long count = -1;
    if (!read_ply_count(words[2], &count) || count < 0 || count > 0x7fffffffLL)
      throw InputError(path, where + ": expected 'element NAME COUNT' with 0 <= COUNT < 2^31");
    *element_seen = true;
  } else if (key == "property") {
    if (!*element_seen) throw InputError(path, where + ": property before any element");
    const std::string type = word_count > 1 ? words[1] : std::string();
    if (type == "list") {
      expect_words(5, "property list COUNT_TYPE ITEM_TYPE NAME");
      if (!ply_scalar_size(words[2]) || !ply_scalar_size(words[3]))
        throw InputError(path, where + ": unknown list type '" + words[2] + " " + words[3] + "'");
    } else {
      expect_words(3, "property TYPE NAME");
      if (!ply_scalar_size(type)) throw InputError(path, where + ": unknown property type '" + type + "'");
    }
  } else if (key == "end_header") {
    expect_words(1, "end_header");
  } else if (key != "comment" && key != "obj_info" && !key.empty()) {
    // A line of no PLY keyword outside any definition (Stanford's
    // happy_stand scans carry 'bye' lines) carries nothing a reader needs;
    // OpenMesh skips its words one by one, as it does obj_info's, so the
    // same guard applies. The warning is the caller's to give
    // (io/ply_header.h, ply_header_warning()).
    if (has_keyword)
      throw InputError(path, where + ": a line of no PLY keyword holds one ('" + line +
                                 "'), which OpenMesh would read as one");
  }
}

// Holds the PLY header to OpenMesh's reading of it, so that everything its
// reader would misinterpret (range grids, lists it skips wrongly, counts the
// body cannot hold) is reported up front with a precise message.
ExpectedCounts check_ply_header(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open the file for reading");
  const PlyHeader header = parse_ply_header(in, kOpenMeshHeaderLines);
  if (header.lines.empty()) throw InputError(path, "file is empty, expected a PLY mesh");
  const std::string first = trimmed(header.lines[0].text);
  if (first != "ply" && first != "PLY")
    throw InputError(path, "not a PLY file: the first line should be 'ply'");
  bool element_seen = false;
  for (std::size_t i = 1; i < header.lines.size(); ++i) check_openmesh_words(path, header.lines[i], &element_seen);
  if (!header.ended) throw InputError(path, "PLY header has no end_header line");
  if (!header.has_format) throw InputError(path, "PLY header has no format line");
  const std::uintmax_t size = file_size_or_zero(path);
  const std::uintmax_t body = header.bytes > size ? 0 : size - header.bytes;

  const std::vector<PlyElement>& elements = header.elements;
  for (const PlyElement& e : elements)
    if (e.name == "range_grid")
      throw InputError(path, "is a Stanford range-grid PLY (element range_grid), i.e. one scan, "
                             "not a mesh: read it as a scan (list it in a .conf)");
  const PlyElement* vertex = nullptr;
  const PlyElement* face = nullptr;
  std::uintmax_t min_bytes = 0;  // the least body the header's counts need
  const bool binary = header.format != PlyHeader::Format::ascii;
  for (const PlyElement& e : elements) {
    if (e.name == "vertex") vertex = &e;
    if (e.name == "face") {
      if (!vertex)
        throw InputError(path, "PLY element face comes before element vertex; "
                               "expected the vertices first");
      face = &e;
      const std::vector<PlyProperty>& props = e.properties;
      if (props.empty() || props[0].type != "list" ||
          (props[0].name != "vertex_indices" && props[0].name != "vertex_index"))
        throw InputError(path, "PLY element face must start with a list property "
                               "vertex_indices");
      const std::string& count_type = props[0].count_type;
      if (count_type != "uchar" && count_type != "uint8" && count_type != "uint16" &&
          count_type != "int")
        throw InputError(path, "PLY face list count type '" + count_type +
                                   "' is not supported; expected uchar, uint8, uint16 or int");
    }
    std::uintmax_t per = 0;
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
      const PlyProperty& p = e.properties[i];
      const bool list = p.type == "list";
      // OpenMesh skips the fields of other elements one scalar at a time, so
      // a list anywhere before the faces would shift everything after it.
      if (list && !(&e == face && i == 0))
        throw InputError(path, "PLY element " + e.name + " has a list property '" + p.name +
                                   "'; only face vertex_indices may be a list");
      per += binary ? std::uintmax_t(list ? ply_scalar_size(p.count_type) + 3 * ply_scalar_size(p.index_type)
                                          : ply_scalar_size(p.type))
                    : (list ? 8 : 2);  // "3 a b c " / "v "
    }
    min_bytes += per * e.count;
    if (&e == face) break;  // nothing after the faces is read
  }
  if (!vertex || vertex->count == 0) throw InputError(path, "has no vertices");
  {
    int xyz = 0;
    for (const PlyProperty& p : vertex->properties) xyz += p.name == "x" || p.name == "y" || p.name == "z";
    if (xyz != 3) throw InputError(path, "PLY element vertex needs properties x, y and z");
  }
  if (!face || face->count == 0)
    throw InputError(path, "has no faces (element face is missing or empty): expected a "
                           "triangle mesh, not a point cloud");
  if (min_bytes > body)
    throw InputError(path, "is truncated: the header promises " + std::to_string(vertex->count) +
                               " vertices and " + std::to_string(face->count) +
                               " faces, which need at least " + std::to_string(min_bytes) +
                               " bytes, but only " + std::to_string(body) + " follow the header");
  return {true, vertex->count, face->count};
}

// Reads the OFF header counts, so that truncation is reported as such.
ExpectedCounts check_off_header(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open the file for reading");
  std::string first;
  std::getline(in, first);
  std::size_t at = first.find("OFF");
  if (at == std::string::npos || at > 4)
    throw InputError(path, "not an OFF file: the first line should be [ST][C][N]OFF [BINARY]");
  if (first.find('4') < at || first.find('n') < at)
    throw InputError(path, "4OFF / nOFF (non-3D vertices) is not supported");
  const bool binary = first.find("BINARY") != std::string::npos;
  std::uint64_t nv = 0, nf = 0;
  if (binary) {
    std::uint32_t c[3];
    if (!in.read(reinterpret_cast<char*>(c), sizeof c))
      throw InputError(path, "OFF header: missing vertex/face/edge counts");
    nv = c[0];
    nf = c[1];
  } else {
    long long v = -1, f = -1;
    in >> v >> f;
    if (!in || v < 0 || f < 0 || v > 0x7fffffffLL || f > 0x7fffffffLL)
      throw InputError(path, "OFF header: expected 'VERTICES FACES EDGES' counts on the "
                             "second line (comment lines are not supported)");
    nv = std::uint64_t(v);
    nf = std::uint64_t(f);
  }
  if (nv == 0) throw InputError(path, "has no vertices");
  if (nf == 0) throw InputError(path, "has no faces: expected a triangle mesh");
  const std::uint64_t min_bytes = binary ? nv * 12 + nf * 16 : nv * 6 + nf * 8;
  if (min_bytes > file_size_or_zero(path))
    throw InputError(path, "is truncated: the header promises " + std::to_string(nv) +
                               " vertices and " + std::to_string(nf) + " faces");
  return {true, nv, nf};
}

TriangleMesh read_with_openmesh(const std::string& path, const std::string& ext) {
  ExpectedCounts expected;
  if (ext == ".ply") expected = check_ply_header(path);
  if (ext == ".off") expected = check_off_header(path);

  // A face needs at least a few bytes on disk, so this bounds what a lying
  // header can make us reserve.
  FlatImporter importer(std::size_t(file_size_or_zero(path) / 4 + 16));
  omio::Options opt = omio::Options::VertexNormal | omio::Options::VertexColor;
  bool ok = false;
  std::string failure;
  {
    std::lock_guard<std::mutex> lock(openmesh_io_mutex());
    QuietOpenMesh quiet;
    try {
      if (ext == ".ply" || ext == ".off") {
        // OpenMesh's PLY and OFF readers keep looping on a failed stream with
        // stale counts; with exceptions on, the first bad read stops them.
        std::ifstream in(path, std::ios::binary);
        if (!in) throw InputError(path, "cannot open the file for reading");
        in.exceptions(std::ios::failbit | std::ios::badbit);
        importer.prepare();
        if (ext == ".ply") {
          ok = omio::PLYReader().read(in, importer, opt);
        } else {
          ok = omio::OFFReader().can_u_read(path) && omio::OFFReader().read(in, importer, opt);
        }
        importer.finish();
      } else {
        ok = omio::STLReader().read(path, importer, opt);
      }
    } catch (const std::ios_base::failure&) {
      // A stream ran dry or held text where a number belonged. A reader may
      // also look one token past a complete file; the count check below decides.
      ok = expected.known && importer.positions.size() == expected.vertices &&
           importer.faces_seen == expected.faces;
      if (!ok) failure = "unexpected end of file or unreadable value";
    } catch (const std::bad_alloc&) {
      failure = "a count in the file is too large to be real";
    } catch (const std::length_error&) {
      failure = "a count in the file is too large to be real";
    }
  }
  const std::string format = ext.substr(1);
  if (!failure.empty() || !ok)
    throw InputError(path, "cannot parse as " + format +
                               (failure.empty() ? std::string() : ": " + failure) +
                               " (read " + std::to_string(importer.positions.size()) +
                               " vertices and " + std::to_string(importer.faces_seen) +
                               " faces before stopping)");
  if (importer.bad_face != SIZE_MAX)
    throw InputError(path, "face " + std::to_string(importer.bad_face) + " " +
                               importer.bad_face_why);
  if (expected.known && (importer.positions.size() != expected.vertices ||
                         importer.faces_seen != expected.faces))
    throw InputError(path, "is truncated or garbled: the header promises " +
                               std::to_string(expected.vertices) + " vertices and " +
                               std::to_string(expected.faces) + " faces, read " +
                               std::to_string(importer.positions.size()) + " and " +
                               std::to_string(importer.faces_seen));

  TriangleMesh mesh;
  mesh.positions = std::move(importer.positions);
  mesh.triangles = std::move(importer.triangles);
  if (importer.saw_normal && opt.vertex_has_normal()) mesh.normals = std::move(importer.normals);
  if (importer.saw_color && opt.vertex_has_color()) mesh.colors = std::move(importer.colors);
  return mesh;
}

// ---------------------------------------------------------------------------
// OBJ. Read here rather than by OpenMesh: Debian builds OpenMesh with
// assertions on, and its OBJ reader aborts on a face line without a usable
// vertex. OBJ is line-oriented, so every error can name its line.

// Parses the next number from `text` (skipping blanks); false when there is none.
template <typename T>
bool next_number(std::string_view& text, T& value) {
  std::size_t start = text.find_first_not_of(" \t\r");
  if (start == std::string_view::npos) return false;
  text.remove_prefix(start);
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc()) return false;
  text.remove_prefix(std::size_t(end - text.data()));
  return true;
}

// With `exact`, the positions in double as well (the floats are parsed from
// the text too, so that they are what read_mesh(path) gives, bit for bit).
TriangleMesh read_obj(const std::string& path, std::vector<Vec3d>* exact) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open the file for reading");
  TriangleMesh mesh;
  std::vector<Vec3f> vn;                 // the file's normal list
  std::vector<std::int32_t> normal_of;   // per vertex: index into vn, or -1
  std::vector<Vec3f> color_values;       // "v x y z r g b", 0..1
  bool any_color = false, any_normal = false;
  std::vector<std::int32_t> corners, corner_normals;
  std::string line;
  for (std::size_t number = 1; std::getline(in, line); ++number) {
    auto fail = [&](const std::string& what) -> InputError {
      return InputError(path, "line " + std::to_string(number) + ": " + what);
    };
    std::string_view text(line);
    const std::size_t start = text.find_first_not_of(" \t");
    if (start == std::string_view::npos) continue;
    text.remove_prefix(start);
    const std::size_t key_end = text.find_first_of(" \t");
    const std::string_view key = text.substr(0, key_end);
    text.remove_prefix(key_end == std::string_view::npos ? text.size() : key_end);
    if (key == "v") {
      Vec3f p;
      const std::string_view coordinates = text;
      if (!next_number(text, p.x()) || !next_number(text, p.y()) || !next_number(text, p.z()))
        throw fail("expected 'v X Y Z'");
      if (exact) {
        Vec3d q;
        std::string_view again = coordinates;
        if (!next_number(again, q.x()) || !next_number(again, q.y()) || !next_number(again, q.z()))
          throw fail("expected 'v X Y Z'");
        exact->push_back(q);
      }
      Vec3f rgb;
      const bool has_rgb =
          next_number(text, rgb.x()) && next_number(text, rgb.y()) && next_number(text, rgb.z());
      mesh.positions.push_back(p);
      normal_of.push_back(-1);
      color_values.push_back(has_rgb ? rgb : Vec3f::Zero());
      any_color |= has_rgb;
    } else if (key == "vn") {
      Vec3f n;
      if (!next_number(text, n.x()) || !next_number(text, n.y()) || !next_number(text, n.z()))
        throw fail("expected 'vn X Y Z'");
      vn.push_back(n);
    } else if (key == "f") {
      corners.clear();
      corner_normals.clear();
      // Corners are V, V/T, V//N or V/T/N; negative indices count back from the end.
      auto resolve = [&](long long i, std::size_t count, const char* list) -> std::int32_t {
        long long r = i > 0 ? i - 1 : (long long)count + i;
        if (i == 0 || r < 0 || r >= (long long)count)
          throw fail("face names " + std::string(list) + " " + std::to_string(i) + " but " +
                     std::to_string(count) + " are defined so far");
        return std::int32_t(r);
      };
      while (true) {
        long long v;
        if (!next_number(text, v)) break;
        corners.push_back(resolve(v, mesh.positions.size(), "vertex"));
        std::int32_t n = -1;
        if (!text.empty() && text.front() == '/') {
          text.remove_prefix(1);
          long long t;
          if (!text.empty() && text.front() != '/' && !next_number(text, t))
            throw fail("bad texture index in face");
          if (!text.empty() && text.front() == '/') {
            text.remove_prefix(1);
            long long ni;
            if (!next_number(text, ni)) throw fail("bad normal index in face");
            n = resolve(ni, vn.size(), "normal");
          }
        }
        corner_normals.push_back(n);
        if (!text.empty() && text.front() != ' ' && text.front() != '\t' && text.front() != '\r')
          throw fail("unexpected '" + std::string(1, text.front()) + "' in face");
      }
      if (text.find_first_not_of(" \t\r") != std::string_view::npos)
        throw fail("unexpected text after the face's corners");
      if (corners.size() < 3) throw fail("a face needs at least 3 corners");
      for (std::size_t k = 0; k < corners.size(); ++k)
        if (corner_normals[k] >= 0) {
          normal_of[std::size_t(corners[k])] = corner_normals[k];
          any_normal = true;
        }
      for (std::size_t k = 1; k + 1 < corners.size(); ++k)
        mesh.triangles.push_back({corners[0], corners[k], corners[k + 1]});
    }
    // vt, g, o, s, usemtl, mtllib, l, p, comments: nothing this project keeps.
  }
  if (in.bad()) throw InputError(path, "read error");

  // Normals count only when every vertex a face uses got one.
  if (any_normal) {
    std::vector<char> used(mesh.positions.size(), 0);
    for (const Triangle& t : mesh.triangles)
      for (std::int32_t v : t) used[std::size_t(v)] = 1;
    bool complete = true;
    for (std::size_t v = 0; v < used.size(); ++v) complete &= !used[v] || normal_of[v] >= 0;
    if (complete) {
      mesh.normals.resize(mesh.positions.size(), Vec3f::Zero());
      for (std::size_t v = 0; v < used.size(); ++v)
        if (normal_of[v] >= 0) mesh.normals[v] = vn[std::size_t(normal_of[v])];
    }
  }
  if (any_color) {
    mesh.colors.resize(mesh.positions.size());
    for (std::size_t v = 0; v < color_values.size(); ++v)
      for (int c = 0; c < 3; ++c)
        mesh.colors[v][c] =
            std::uint8_t(std::lround(std::clamp(color_values[v][c], 0.f, 1.f) * 255.f));
  }
  return mesh;
}


// ---------------------------------------------------------------------------
// Writing: an exporter that serves OpenMesh's writers from the flat arrays.

class FlatExporter : public omio::BaseExporter {
 public:
  // Positions go out as origin + position, rounded to floats (STL: write_mesh
  // has checked that floats hold them); zero writes the floats as they are.
  FlatExporter(const TriangleMesh& mesh, const Vec3d& origin) : m_(mesh), origin_(origin) {}

  OpenMesh::Vec3f point(OpenMesh::VertexHandle vh) const override {
    const Vec3f& p = m_.positions[std::size_t(vh.idx())];
    if (origin_ == Vec3d::Zero()) return {p.x(), p.y(), p.z()};
    const Vec3f q = (origin_ + p.cast<double>()).cast<float>();
    return {q.x(), q.y(), q.z()};
  }
  OpenMesh::Vec3d pointd(OpenMesh::VertexHandle vh) const override {
    return OpenMesh::vector_cast<OpenMesh::Vec3d>(point(vh));
  }
  bool is_point_double() const override { return false; }
  OpenMesh::Vec3f normal(OpenMesh::VertexHandle vh) const override {
    if (m_.normals.empty()) return {0, 0, 0};
    const Vec3f& n = m_.normals[std::size_t(vh.idx())];
    return {n.x(), n.y(), n.z()};
  }
  OpenMesh::Vec3d normald(OpenMesh::VertexHandle vh) const override {
    return OpenMesh::vector_cast<OpenMesh::Vec3d>(normal(vh));
  }
  bool is_normal_double() const override { return false; }
  OpenMesh::Vec3uc color(OpenMesh::VertexHandle vh) const override {
    if (m_.colors.empty()) return {0, 0, 0};
    const Rgb& c = m_.colors[std::size_t(vh.idx())];
    return {c[0], c[1], c[2]};
  }
  OpenMesh::Vec4uc colorA(OpenMesh::VertexHandle vh) const override {
    OpenMesh::Vec3uc c = color(vh);
    return {c[0], c[1], c[2], 255};
  }
  OpenMesh::Vec3ui colori(OpenMesh::VertexHandle vh) const override {
    OpenMesh::Vec3uc c = color(vh);
    return {c[0], c[1], c[2]};
  }
  OpenMesh::Vec4ui colorAi(OpenMesh::VertexHandle vh) const override {
    OpenMesh::Vec3uc c = color(vh);
    return {c[0], c[1], c[2], 255};
  }
  OpenMesh::Vec3f colorf(OpenMesh::VertexHandle vh) const override {
    OpenMesh::Vec3uc c = color(vh);
    return {c[0] / 255.f, c[1] / 255.f, c[2] / 255.f};
  }
  OpenMesh::Vec4f colorAf(OpenMesh::VertexHandle vh) const override {
    OpenMesh::Vec3f c = colorf(vh);
    return {c[0], c[1], c[2], 1.f};
  }
  OpenMesh::Vec2f texcoord(OpenMesh::VertexHandle) const override { return {0, 0}; }
  OpenMesh::Vec2f texcoord(OpenMesh::HalfedgeHandle) const override { return {0, 0}; }
  OpenMesh::Attributes::StatusInfo status(OpenMesh::VertexHandle) const override { return {}; }

  unsigned int get_vhandles(OpenMesh::FaceHandle fh,
                            std::vector<OpenMesh::VertexHandle>& corners) const override {
    const Triangle& t = m_.triangles[std::size_t(fh.idx())];
    corners.resize(3);
    for (int k = 0; k < 3; ++k) corners[std::size_t(k)] = OpenMesh::VertexHandle(t[std::size_t(k)]);
    return 3;
  }
  OpenMesh::HalfedgeHandle getHeh(OpenMesh::FaceHandle, OpenMesh::VertexHandle) const override {
    return OpenMesh::HalfedgeHandle();
  }
  unsigned int get_face_texcoords(std::vector<OpenMesh::Vec2f>&) const override { return 0; }
  OpenMesh::Vec3f normal(OpenMesh::FaceHandle fh) const override {
    // Local positions: a facet's normal does not depend on where it lies.
    const Triangle& t = m_.triangles[std::size_t(fh.idx())];
    const Vec3f& a = m_.positions[t[0]];
    Vec3f n = (m_.positions[t[1]] - a).cross(m_.positions[t[2]] - a);
    if (n.norm() > 0) n.normalize();
    return {n.x(), n.y(), n.z()};
  }
  OpenMesh::Vec3d normald(OpenMesh::FaceHandle fh) const override {
    return OpenMesh::vector_cast<OpenMesh::Vec3d>(normal(fh));
  }
  OpenMesh::Vec3uc color(OpenMesh::FaceHandle) const override { return {0, 0, 0}; }
  OpenMesh::Vec4uc colorA(OpenMesh::FaceHandle) const override { return {0, 0, 0, 255}; }
  OpenMesh::Vec3ui colori(OpenMesh::FaceHandle) const override { return {0, 0, 0}; }
  OpenMesh::Vec4ui colorAi(OpenMesh::FaceHandle) const override { return {0, 0, 0, 255}; }
  OpenMesh::Vec3f colorf(OpenMesh::FaceHandle) const override { return {0, 0, 0}; }
  OpenMesh::Vec4f colorAf(OpenMesh::FaceHandle) const override { return {0, 0, 0, 1}; }
  OpenMesh::Attributes::StatusInfo status(OpenMesh::FaceHandle) const override { return {}; }
  OpenMesh::Vec3uc color(OpenMesh::EdgeHandle) const override { return {0, 0, 0}; }
  OpenMesh::Vec4uc colorA(OpenMesh::EdgeHandle) const override { return {0, 0, 0, 255}; }
  OpenMesh::Vec3ui colori(OpenMesh::EdgeHandle) const override { return {0, 0, 0}; }
  OpenMesh::Vec4ui colorAi(OpenMesh::EdgeHandle) const override { return {0, 0, 0, 255}; }
  OpenMesh::Vec3f colorf(OpenMesh::EdgeHandle) const override { return {0, 0, 0}; }
  OpenMesh::Vec4f colorAf(OpenMesh::EdgeHandle) const override { return {0, 0, 0, 1}; }
  OpenMesh::Attributes::StatusInfo status(OpenMesh::EdgeHandle) const override { return {}; }
  int get_halfedge_id(OpenMesh::VertexHandle) override { return -1; }
  int get_halfedge_id(OpenMesh::FaceHandle) override { return -1; }
  int get_next_halfedge_id(OpenMesh::HalfedgeHandle) override { return -1; }
  int get_to_vertex_id(OpenMesh::HalfedgeHandle) override { return -1; }
  int get_face_id(OpenMesh::HalfedgeHandle) override { return -1; }
  OpenMesh::Attributes::StatusInfo status(OpenMesh::HalfedgeHandle) const override { return {}; }

  // The PLY writer lists a kernel's custom properties; an empty kernel has none.
  const OpenMesh::BaseKernel* kernel() override { return &no_properties_; }

  size_t n_vertices() const override { return m_.positions.size(); }
  size_t n_faces() const override { return m_.triangles.size(); }
  size_t n_edges() const override { return 0; }
  bool is_triangle_mesh() const override { return true; }
  bool has_vertex_normals() const override { return !m_.normals.empty(); }
  bool has_vertex_colors() const override { return !m_.colors.empty(); }
  bool has_face_normals() const override { return true; }  // computed from corners (STL)

 private:
  const TriangleMesh& m_;
  const Vec3d origin_;
  OpenMesh::BaseKernel no_properties_;
};

void check_consistent(const std::string& path, const TriangleMesh& mesh) {
  const std::size_t n = mesh.positions.size();
  if (!mesh.normals.empty() && mesh.normals.size() != n)
    throw InputError(path, "cannot write: the mesh has " + std::to_string(mesh.normals.size()) +
                               " normals for " + std::to_string(n) + " vertices");
  if (!mesh.colors.empty() && mesh.colors.size() != n)
    throw InputError(path, "cannot write: the mesh has " + std::to_string(mesh.colors.size()) +
                               " colours for " + std::to_string(n) + " vertices");
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (std::int32_t v : mesh.triangles[t])
      if (v < 0 || std::size_t(v) >= n)
        throw InputError(path, "cannot write: triangle " + std::to_string(t) + " names vertex " +
                                   std::to_string(v) + " of " + std::to_string(n));
}

void write_with_openmesh(const std::string& tmp, const std::string& final_path,
                         const std::string& ext, const TriangleMesh& mesh, const Vec3d& origin) {
  FlatExporter exporter(mesh, origin);
  omio::Options opt = omio::Options::Default;
  const bool has_n = !mesh.normals.empty(), has_c = !mesh.colors.empty();
  const omio::BaseWriter* writer = nullptr;
  if (ext == ".ply") {
    writer = &omio::PLYWriter();
    opt += omio::Options::Binary;
    opt += omio::Options::LSB;
    if (has_n) opt += omio::Options::VertexNormal;
    if (has_c) opt += omio::Options::VertexColor;
  } else if (ext == ".off") {
    writer = &omio::OFFWriter();
    if (has_n) opt += omio::Options::VertexNormal;
    // RGBA, not RGB: readers such as Open3D's take COFF colours as four values.
    if (has_c) opt += omio::Options::VertexColor, opt += omio::Options::ColorAlpha;
  } else {
    writer = &omio::STLWriter();
    opt += omio::Options::Binary;
  }
  std::ofstream out(tmp, std::ios::binary);
  if (!out) throw InputError(final_path, "cannot create the file (does the folder exist?)");
  bool ok;
  {
    std::lock_guard<std::mutex> lock(openmesh_io_mutex());
    QuietOpenMesh quiet;
    // 9 significant digits round-trip a float exactly through ASCII formats.
    ok = writer->write(out, exporter, opt, 9);
  }
  out.close();
  if (!ok || out.fail())
    throw InputError(final_path, "writing " + ext.substr(1) + " failed (disk full?)");
}


// STL holds floats only: refuses a mesh within the box [low, high] (local)
// about `origin` when floats do not hold that box in the file's frame
// (io/local_origin.h), naming the formats that keep it.
void check_stl_holds(const std::string& path, const Vec3d& origin, const Vec3d& low, const Vec3d& high) {
  if (origin == Vec3d::Zero() || floats_hold(origin + low, origin + high)) return;
  char what[512];
  std::snprintf(what, sizeof what,
                "cannot write STL in the file's frame: STL holds 32-bit floats only, which there (origin "
                "%.17g, %.17g, %.17g) would move vertices by up to %.3g, more than a millionth of the mesh's "
                "size; write .ply, .obj, .off, .vtp, .glb or .gltf, which keep it",
                origin.x(), origin.y(), origin.z(), float_rounding(origin + low, origin + high));
  throw InputError(path, what);
}

const char* const kFormats = ".ply, .obj, .off, .stl, .vtp, .glb or .gltf";
const char* const kOutputFormats = ".ply, .obj, .off, .stl, .vtp, .glb or .gltf";

// The mesh `path` holds: as floats in the file's frame without `origin`, or
// about the local origin it sets (read_mesh with an origin, io/mesh_file.h).
TriangleMesh read_any(const std::string& path, Vec3d* origin) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, "file not found");
  if (fs::is_directory(path, ec)) throw InputError(path, "is a folder, expected a mesh file");
  const std::string ext = lower_extension(path);
  // Positions in double where the file holds more than floats; left empty
  // where the floats are what the file holds.
  std::vector<Vec3d> exact;
  std::vector<Vec3d>* want = origin ? &exact : nullptr;
  TriangleMesh mesh;
  if (ext == ".ply" || ext == ".off" || ext == ".stl") {
    mesh = read_with_openmesh(path, ext);
    if (want && ext == ".ply") exact = read_ply_double_positions(path);
    if (want && ext == ".off") exact = read_off_double_positions(path, mesh.positions.size());
  } else if (ext == ".obj") {
    mesh = read_obj(path, want);
  } else if (ext == ".vtp") {
    mesh = read_vtp(path, want);
  } else if (is_gltf_path(path)) {
    return origin ? read_gltf(path, origin) : read_gltf(path);  // node transforms in double there
  } else {
    throw InputError(path, "unknown mesh extension '" + ext + "', expected " + kFormats);
  }
  if (!origin) return mesh;
  if (!exact.empty() && exact.size() != mesh.positions.size())
    throw InputError(path, "holds " + std::to_string(exact.size()) + " vertex positions in double for " +
                               std::to_string(mesh.positions.size()) + " vertices");
  *origin = local_origin(exact);
  if (*origin != Vec3d::Zero()) mesh.positions = positions_about(exact, *origin);
  return mesh;
}

// What every mesh read must have.
void check_read(const std::string& path, const TriangleMesh& mesh) {
  if (mesh.positions.empty()) throw InputError(path, "has no vertices");
  if (mesh.triangles.empty())
    throw InputError(path, "has no faces: expected a triangle mesh, not a point cloud");
  for (std::size_t i = 0; i < mesh.positions.size(); ++i)
    if (!mesh.positions[i].allFinite())
      throw InputError(path, "vertex " + std::to_string(i) + " has a coordinate that is not a "
                             "finite number");
}

}  // namespace

TriangleMesh read_mesh(const std::string& path) {
  TriangleMesh mesh = read_any(path, nullptr);
  check_read(path, mesh);
  return mesh;
}

TriangleMesh read_mesh(const std::string& path, Vec3d* origin) {
  TriangleMesh mesh = read_any(path, origin);
  check_read(path, mesh);
  return mesh;
}

void check_mesh_output(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext != ".ply" && ext != ".obj" && ext != ".off" && ext != ".stl" && ext != ".vtp" && !is_gltf_path(path))
    throw InputError(path, "unknown mesh extension '" + ext + "', expected " + kOutputFormats);
  check_output_path(path);
}

void check_mesh_output(const std::string& path, const Vec3d& origin, const Aabb& bounds) {
  check_mesh_output(path);
  if (!origin.allFinite()) throw InputError(path, "cannot write: the origin is not a finite point");
  if (lower_extension(path) == ".stl" && !bounds.empty())
    check_stl_holds(path, origin, bounds.min.cast<double>(), bounds.max.cast<double>());
}

std::size_t write_mesh(const std::string& path, const TriangleMesh& mesh, const MeshWriteOptions& options) {
  check_mesh_output(path);
  const std::string ext = lower_extension(path);
  check_consistent(path, mesh);
  if (mesh.triangles.empty()) throw InputError(path, "cannot write: the mesh has no triangles");
  std::optional<UsedVertices> used = drop_unused_vertices(mesh, {&mesh.triangles});
  if (used) used->vertices.triangles = std::move(used->lists[0]);
  const TriangleMesh& out = used ? used->vertices : mesh;
  const Vec3d& origin = options.origin;
  if (!origin.allFinite()) throw InputError(path, "cannot write: the origin is not a finite point");
  if (is_gltf_path(path)) {
    GltfOptions gltf;
    gltf.quantize = options.quantize;
    gltf.generator = options.generator;
    gltf.origin = origin;
    write_gltf(path, out, gltf);
    return out.positions.size();
  }
  const bool framed = origin != Vec3d::Zero();
  if (framed && ext == ".stl") {
    const Aabb box = bounds(out.positions);
    check_stl_holds(path, origin, box.min.cast<double>(), box.max.cast<double>());
  }
  write_atomically(path, [&](const std::string& tmp) {
    if (ext == ".vtp")
      write_vtp(tmp, path, out, origin);
    else if (ext == ".obj")
      write_obj(tmp, path, out, origin);
    else if (framed && ext == ".ply")
      write_ply_in_frame(tmp, path, out, origin);
    else if (framed && ext == ".off")
      write_off_in_frame(tmp, path, out, origin);
    else
      write_with_openmesh(tmp, path, ext, out, origin);
  });
  return out.positions.size();
}

}  // namespace scan2lod
