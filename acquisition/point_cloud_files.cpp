#include <scan2lod/acquisition/point_cloud_files.h>

#include <scan2lod/acquisition/text_records.h>
#include <scan2lod/core/error.h>
#include <scan2lod/io/atomic_file.h>
#include <scan2lod/io/ply_header.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

namespace scan2lod {
namespace {

bool little_endian() {
  const std::uint16_t one = 1;
  unsigned char first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

// ---------------------------------------------------------------------------
// PLY

enum class Scalar { i8, u8, i16, u16, i32, u32, f32, f64 };

bool scalar_type(const std::string& t, Scalar* s) {
  static const std::pair<const char*, Scalar> names[] = {
      {"char", Scalar::i8},   {"int8", Scalar::i8},     {"uchar", Scalar::u8},   {"uint8", Scalar::u8},
      {"short", Scalar::i16}, {"int16", Scalar::i16},   {"ushort", Scalar::u16}, {"uint16", Scalar::u16},
      {"int", Scalar::i32},   {"int32", Scalar::i32},   {"uint", Scalar::u32},   {"uint32", Scalar::u32},
      {"float", Scalar::f32}, {"float32", Scalar::f32}, {"double", Scalar::f64}, {"float64", Scalar::f64}};
  for (const auto& [name, scalar] : names)
    if (t == name) return *s = scalar, true;
  return false;
}

std::size_t scalar_size(Scalar s) {
  switch (s) {
    case Scalar::i8: case Scalar::u8: return 1;
    case Scalar::i16: case Scalar::u16: return 2;
    case Scalar::i32: case Scalar::u32: case Scalar::f32: return 4;
    case Scalar::f64: return 8;
  }
  return 0;
}

struct VertexLayout {
  PlyHeader::Format format = PlyHeader::Format::ascii;
  std::string warning;  // header lines skipped
  std::size_t header_bytes = 0;
  std::size_t vertices = 0;
  std::vector<Scalar> types;
  std::vector<std::size_t> offsets;  // bytes into a binary vertex
  std::size_t stride = 0;
  int xyz[3] = {-1, -1, -1}, normal[3] = {-1, -1, -1}, rgb[3] = {-1, -1, -1};  // property slots
};

// Which of the roles a vertex property plays: 0-2 position, 3-5 normal, 6-8 colour.
int property_role(const std::string& name) {
  static const char* roles[9][3] = {{"x", "x", "x"},
                                    {"y", "y", "y"},
                                    {"z", "z", "z"},
                                    {"nx", "normal_x", "normalx"},
                                    {"ny", "normal_y", "normaly"},
                                    {"nz", "normal_z", "normalz"},
                                    {"red", "r", "diffuse_red"},
                                    {"green", "g", "diffuse_green"},
                                    {"blue", "b", "diffuse_blue"}};
  for (int r = 0; r < 9; ++r)
    for (const char* n : roles[r])
      if (name == n) return r;
  return -1;
}

// The header is read by read_ply_header and judged here, each complaint
// naming the line.
VertexLayout read_vertex_layout(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file");
  const PlyHeader h = read_ply_header(path, in);
  VertexLayout L;
  L.format = h.format;
  L.header_bytes = h.bytes;
  L.warning = ignored_lines_warning(path, h);
  const bool seen_format = h.has_format;
  bool seen_vertex = false;
  for (const PlyElement& e : h.elements) {
    if (e.name == "vertex") {
      if (seen_vertex) fail_at(path, e.line, "element 'vertex' appears twice");
      if (e.count > 0x7fffffffULL) fail_at(path, e.line, "more than 2^31 vertices");
      seen_vertex = true;
      L.vertices = e.count;
    } else if (e.name == "face" && e.count > 0) {
      fail_at(path, e.line, "the file has faces: a mesh, not a point cloud");
    } else if (!seen_vertex && e.count > 0) {
      fail_at(path, e.line, "element '" + e.name + "' before the vertices; a point cloud PLY starts with its vertices");
    }
    if (e.name != "vertex") continue;  // other elements are not read
    for (const PlyProperty& p : e.properties) {
      Scalar s;
      if (p.type == "list") fail_at(path, p.line, "vertex properties must be scalars");
      if (!scalar_type(p.type, &s)) fail_at(path, p.line, "unknown property type '" + p.type + "'");
      const int role = property_role(p.name);
      const int slot = int(L.types.size());
      if (role >= 0) {
        int* target = role < 3 ? &L.xyz[role] : role < 6 ? &L.normal[role - 3] : &L.rgb[role - 6];
        if (*target >= 0) fail_at(path, p.line, "property '" + p.name + "' given twice");
        if (role < 6 && s != Scalar::f32 && s != Scalar::f64) fail_at(path, p.line, "'" + p.name + "' must be float or double");
        *target = slot;
      }
      L.types.push_back(s);
      L.offsets.push_back(L.stride);
      L.stride += scalar_size(s);
    }
  }
  if (!seen_format) throw InputError(path, "PLY header has no 'format' line");
  if (!seen_vertex || L.vertices == 0) throw InputError(path, "PLY file has no vertices");
  if (L.xyz[0] < 0 || L.xyz[1] < 0 || L.xyz[2] < 0)
    throw InputError(path, "element vertex lacks a float x, y or z property");
  const bool normals = L.normal[0] >= 0 || L.normal[1] >= 0 || L.normal[2] >= 0;
  if (normals && (L.normal[0] < 0 || L.normal[1] < 0 || L.normal[2] < 0))
    throw InputError(path, "element vertex has some of nx, ny, nz but not all three");
  const bool colors = L.rgb[0] >= 0 || L.rgb[1] >= 0 || L.rgb[2] >= 0;
  if (colors && (L.rgb[0] < 0 || L.rgb[1] < 0 || L.rgb[2] < 0 || L.types[L.rgb[0]] != Scalar::u8 ||
                 L.types[L.rgb[1]] != Scalar::u8 || L.types[L.rgb[2]] != Scalar::u8))
    L.rgb[0] = L.rgb[1] = L.rgb[2] = -1;  // partial or non-byte colour: ignored
  return L;
}

double decode(const unsigned char* p, Scalar s, bool swap) {
  unsigned char b[8];
  const std::size_t n = scalar_size(s);
  for (std::size_t i = 0; i < n; ++i) b[i] = swap ? p[n - 1 - i] : p[i];
  switch (s) {
    case Scalar::i8: return double(std::int8_t(b[0]));
    case Scalar::u8: return double(b[0]);
    case Scalar::i16: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
    case Scalar::u16: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
    case Scalar::i32: { std::int32_t v; std::memcpy(&v, b, 4); return v; }
    case Scalar::u32: { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
    case Scalar::f32: { float v; std::memcpy(&v, b, 4); return v; }
    case Scalar::f64: { double v; std::memcpy(&v, b, 8); return v; }
  }
  return 0.0;
}

// Stores vertex i's decoded property values into the cloud.
void store_vertex(const VertexLayout& L, const double* values, std::size_t i, PointCloud* cloud) {
  cloud->positions[i] = Vec3f(float(values[L.xyz[0]]), float(values[L.xyz[1]]), float(values[L.xyz[2]]));
  if (!cloud->normals.empty())
    cloud->normals[i] = Vec3f(float(values[L.normal[0]]), float(values[L.normal[1]]), float(values[L.normal[2]]));
  if (!cloud->colors.empty())
    for (int c = 0; c < 3; ++c) cloud->colors[i][c] = std::uint8_t(std::clamp(values[L.rgb[c]], 0.0, 255.0));
}

// Parses the blank-separated numbers of a line into values (at most max);
// returns how many there were, or -1 for a token that is not a number.
int parse_numbers(std::string_view line, double* values, int max) {
  int count = 0;
  std::size_t at = 0;
  while (true) {
    while (at < line.size() && (line[at] == ' ' || line[at] == '\t' || line[at] == ',')) ++at;
    if (at >= line.size()) return count;
    std::size_t end = at;
    while (end < line.size() && line[end] != ' ' && line[end] != '\t' && line[end] != ',') ++end;
    double v;
    const char* first = line.data() + at;
    if (*first == '+') ++first;
    auto [ptr, ec] = std::from_chars(first, line.data() + end, v);
    if (ec != std::errc() || ptr != line.data() + end) return -1;
    if (count < max) values[count] = v;
    ++count;
    at = end;
  }
}

void read_ply_body(const std::string& path, const VertexLayout& L, PointCloud* cloud) {
  const std::size_t n = L.vertices;
  std::vector<double> values(L.types.size());
  if (L.format == PlyHeader::Format::ascii) {
    // Vertex lines are the body's first n that are not blank, parsed on all cores.
    const std::string text = read_file_from(path, L.header_bytes);
    auto not_blank = [](std::string_view line) { return line.find_first_not_of(" \t") != std::string_view::npos; };
    const std::vector<TextBlock> blocks = cut_records(text, 1, n, not_blank);
    if (record_count(blocks) < n)
      throw InputError(path, "file ends at vertex " + std::to_string(record_count(blocks)) + " of " + std::to_string(n) +
                                 " (truncated)");
    const std::size_t properties = L.types.size();
    parse_records(blocks, not_blank, [&](std::string_view line, std::size_t, std::size_t i) {
      double few[64];
      std::vector<double> many(properties > 64 ? properties : 0);
      double* v = properties > 64 ? many.data() : few;
      const int count = parse_numbers(line, v, int(properties));
      if (count != int(properties))
        throw InputError(path, "vertex " + std::to_string(i) + " needs " + std::to_string(properties) +
                                   " numbers, got '" + shown_line(std::string(line)) + "'");
      store_vertex(L, v, i, cloud);
    });
    return;
  }
  std::error_code ec;
  const std::uint64_t size = std::filesystem::file_size(path, ec);
  const std::uint64_t need = std::uint64_t(n) * L.stride;
  if (ec || size < L.header_bytes || size - L.header_bytes < need)
    throw InputError(path, "binary data holds fewer bytes than the header's " + std::to_string(n) +
                               " vertices need (" + std::to_string(need) + "): truncated");
  std::ifstream in(path, std::ios::binary);
  in.seekg(std::streamoff(L.header_bytes));
  std::vector<unsigned char> body(need);
  if (!in.read(reinterpret_cast<char*>(body.data()), std::streamsize(need)))
    throw InputError(path, "could not read the vertex data");
  const bool swap = (L.format == PlyHeader::Format::binary_be) == little_endian();
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned char* v = &body[i * L.stride];
    for (std::size_t k = 0; k < L.types.size(); ++k) values[k] = decode(v + L.offsets[k], L.types[k], swap);
    store_vertex(L, values.data(), i, cloud);
  }
}

}  // namespace

PointCloud read_point_cloud_ply(const std::string& path) {
  const VertexLayout L = read_vertex_layout(path);
  // The header's count must fit the file before anything is sized by it:
  // a binary vertex takes its stride, an ASCII one a character and a blank per value.
  std::error_code ec;
  const std::uint64_t size = std::filesystem::file_size(path, ec);
  const std::uint64_t body = ec || size < L.header_bytes ? 0 : size - L.header_bytes;
  const std::uint64_t least = L.format == PlyHeader::Format::ascii ? 2 * L.types.size() : L.stride;
  if (std::uint64_t(L.vertices) > body / std::max<std::uint64_t>(least, 1))
    throw InputError(path, "the header promises " + std::to_string(L.vertices) + " vertices, the file's " +
                               std::to_string(body) + " bytes of data cannot hold them (truncated)");
  PointCloud cloud;
  cloud.source = path;
  cloud.positions.resize(L.vertices);
  if (L.normal[0] >= 0) cloud.normals.resize(L.vertices);
  if (L.rgb[0] >= 0) cloud.colors.resize(L.vertices);
  read_ply_body(path, L, &cloud);
  if (!L.warning.empty()) cloud.warnings.push_back(L.warning);
  return cloud;
}

namespace {

// What the first data line of a .xyz/.pts file says the others hold.
struct TextColumns {
  int columns = 0;
  bool normals = false, colors = false;
};

bool is_data_line(std::string_view line) {
  const std::size_t first = line.find_first_not_of(" \t");
  return first != std::string_view::npos && line[first] != '#' && line.substr(first, 2) != "//";
}

[[noreturn]] void fail_at_line(const std::string& path, std::size_t number, std::string_view line,
                               const std::string& what) {
  throw InputError(path, "line " + std::to_string(number) + " ('" + shown_line(std::string(line)) + "'): " + what);
}

// Phase: the lines up to the first point, which decides the columns; `at`
// is left at that point's line, `number` at its number.
TextColumns read_columns(const std::string& path, std::string_view text, std::size_t* at, std::size_t* number) {
  const char* p = text.data();
  const char* const end = text.data() + text.size();
  for (*number = 1; p < end; ++*number) {
    const char* start = p;
    const std::string_view line = next_line(p, end);
    if (!is_data_line(line)) continue;
    double v[10];
    const int count = parse_numbers(line, v, 10);
    if (count < 0) fail_at_line(path, *number, line, "expected numbers only");
    // A .pts file starts with its point count; lines of a count alone
    // before the first point are skipped, as releases before skipped them.
    if (count == 1 && v[0] >= 0 && v[0] == std::floor(v[0])) continue;
    if (count != 3 && count != 4 && count != 6 && count != 7 && count != 9)
      fail_at_line(path, *number, line,
                   "expected 3 (x y z), 4 (x y z i), 6 (x y z nx ny nz, or x y z r g b), 7 (x y z i r g b) or "
                   "9 (x y z nx ny nz r g b) values, got " + std::to_string(count));
    TextColumns c;
    c.columns = count;
    const double length = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5]);
    c.normals = count == 9 || (count == 6 && std::fabs(length - 1.0) < 0.01);
    c.colors = count == 7 || count == 9 || (count == 6 && !c.normals);
    *at = std::size_t(start - text.data());
    return c;
  }
  throw InputError(path, "holds no points (expected lines of 'x y z ...')");
}

}  // namespace

PointCloud read_point_cloud_text(const std::string& path) {
  const std::string text = read_file_from(path);
  std::size_t at = 0, number = 1;
  const TextColumns c = read_columns(path, text, &at, &number);
  const std::vector<TextBlock> blocks =
      cut_records(std::string_view(text).substr(at), number, std::size_t(-1), is_data_line);
  const std::size_t n = record_count(blocks);
  PointCloud cloud;
  cloud.source = path;
  cloud.positions.resize(n);
  if (c.normals) cloud.normals.resize(n);
  if (c.colors) cloud.colors.resize(n);
  parse_records(blocks, is_data_line, [&](std::string_view line, std::size_t number, std::size_t i) {
    double v[10];
    const int count = parse_numbers(line, v, 10);
    if (count < 0) fail_at_line(path, number, line, "expected numbers only");
    if (count != c.columns)
      fail_at_line(path, number, line,
                   "has " + std::to_string(count) + " values, the first point had " + std::to_string(c.columns));
    cloud.positions[i] = Vec3f(float(v[0]), float(v[1]), float(v[2]));
    if (c.normals) cloud.normals[i] = Vec3f(float(v[3]), float(v[4]), float(v[5]));
    if (c.colors) {
      const int c0 = c.columns == 6 ? 3 : c.columns - 3;
      for (int k = 0; k < 3; ++k) {
        if (!(v[c0 + k] >= 0 && v[c0 + k] <= 255)) fail_at_line(path, number, line, "colour values must lie in 0 to 255");
        cloud.colors[i][std::size_t(k)] = std::uint8_t(v[c0 + k] + 0.5);
      }
    }
  });
  return cloud;
}

void write_point_cloud_ply(const std::string& path, const PointCloud& cloud) {
  const bool normals = cloud.normals.size() == cloud.size() && cloud.size() > 0;
  const bool colors = cloud.colors.size() == cloud.size() && cloud.size() > 0;
  write_atomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\nelement vertex " << cloud.size()
        << "\nproperty float x\nproperty float y\nproperty float z\n";
    if (normals) out << "property float nx\nproperty float ny\nproperty float nz\n";
    if (colors) out << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    out << "end_header\n";
    const bool swap = !little_endian();
    std::vector<char> record;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      record.clear();
      auto put = [&](const float* p) {
        for (int k = 0; k < 3; ++k) {
          char b[4];
          std::memcpy(b, &p[k], 4);
          if (swap) std::reverse(b, b + 4);
          record.insert(record.end(), b, b + 4);
        }
      };
      put(cloud.positions[i].data());
      if (normals) put(cloud.normals[i].data());
      if (colors) record.insert(record.end(), cloud.colors[i].begin(), cloud.colors[i].end());
      out.write(record.data(), std::streamsize(record.size()));
    }
    if (!out) throw InputError(path, "could not write the point cloud");
  });
}

}  // namespace scan2lod
