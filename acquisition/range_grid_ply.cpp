#include <scan2lod/acquisition/range_grid_ply.h>

#include <scan2lod/acquisition/text_records.h>
#include <scan2lod/core/error.h>
#include <scan2lod/io/atomic_file.h>
#include <scan2lod/io/ply_header.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/ply_io.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string_view>
#include <vector>

namespace scan2lod {
namespace {

struct PlyLayout {
  PlyHeader::Format format = PlyHeader::Format::ascii;
  std::string warning;  // header lines skipped
  std::size_t header_bytes = 0;
  std::size_t header_lines = 0;
  long cols = -1, rows = -1;
  std::size_t vertices = 0;
  std::size_t grid_cells = 0;
  std::size_t faces = 0;
  std::size_t vertex_properties = 0;
  std::size_t vertex_stride = 0;  // bytes, binary only
  bool has_xyz[3] = {false, false, false};
  bool has_grid = false;
  bool has_vertex = false;
  std::size_t grid_properties = 0;
  std::size_t grid_count_size = 0;  // bytes of each cell's index count
  bool grid_count_signed = false;
  std::vector<std::string> vertex_names, vertex_types;  // in file order
};

// The header is read by read_ply_header and judged here, not left to PCL, so
// that every complaint names the file and the line; PCL reports most
// problems only as "parse error".
PlyLayout read_layout(const std::string& path, std::ifstream& in) {
  const PlyHeader h = read_ply_header(path, in);
  PlyLayout L;
  L.format = h.format;
  L.header_bytes = h.bytes;
  L.warning = ignored_lines_warning(path, h);
  L.header_lines = h.lines.size();
  for (const PlyHeaderLine& info : h.obj_info) {
    std::istringstream ls(info.text);
    std::string name;
    long value = -1;
    ls >> name;
    if (name == "num_cols" || name == "num_rows") {
      if (!(ls >> value) || value <= 0 || value > 100000) fail_at(path, info, "expected a positive size");
      (name == "num_cols" ? L.cols : L.rows) = value;
    }
  }
  for (const PlyElement& e : h.elements) {
    if ((e.name == "vertex" && L.has_vertex) || (e.name == "range_grid" && L.has_grid))
      fail_at(path, e.line, "element '" + e.name + "' appears twice");
    // The body checks below read the vertices first, as PCL's writer puts them.
    if (e.name == "range_grid" && !L.has_vertex) fail_at(path, e.line, "element range_grid must follow element vertex");
    if (e.name == "vertex") L.vertices = e.count, L.has_vertex = true;
    else if (e.name == "range_grid") L.grid_cells = e.count, L.has_grid = true;
    else if (e.name == "face") L.faces = e.count;
    else if (e.count > 0) fail_at(path, e.line, "unexpected element '" + e.name + "' in a range-grid PLY");
    for (const PlyProperty& p : e.properties) {
      if (e.name == "vertex") {
        if (p.type == "list") fail_at(path, p.line, "vertex properties must be scalars");
        const std::size_t size = ply_scalar_size(p.type);
        if (size == 0) fail_at(path, p.line, "unknown property type '" + p.type + "'");
        ++L.vertex_properties;
        L.vertex_stride += size;
        L.vertex_names.push_back(p.name);
        L.vertex_types.push_back(p.type);
        if (p.name == "x" || p.name == "y" || p.name == "z") {
          if (p.type != "float" && p.type != "float32") fail_at(path, p.line, "x, y, z must be float");
          L.has_xyz[p.name[0] - 'x'] = true;
        }
      } else if (e.name == "range_grid") {
        const std::string& count_type = p.count_type;
        const bool integer_count = count_type.find("int") != std::string::npos ||
                                   count_type.find("char") != std::string::npos ||
                                   count_type.find("short") != std::string::npos;
        const bool integer_index = p.index_type == "int" || p.index_type == "int32" ||
                                   p.index_type == "uint" || p.index_type == "uint32";
        if (p.type != "list" || ply_scalar_size(count_type) == 0 || !integer_count || !integer_index ||
            ++L.grid_properties > 1)
          fail_at(path, p.line, "range_grid must have one property, 'property list uchar int vertex_indices'");
        L.grid_count_size = ply_scalar_size(count_type);
        L.grid_count_signed = count_type[0] != 'u';
      }
    }
  }
  if (!L.has_grid) throw InputError(path, "no 'element range_grid': not a range-grid PLY");
  if (L.cols <= 0 || L.rows <= 0)
    throw InputError(path, "range-grid PLY lacks 'obj_info num_cols' / 'obj_info num_rows'");
  if (std::size_t(L.cols) * std::size_t(L.rows) != L.grid_cells)
    throw InputError(path, "element range_grid has " + std::to_string(L.grid_cells) +
                               " cells, expected num_cols*num_rows = " +
                               std::to_string(L.cols * L.rows));
  if (!(L.has_xyz[0] && L.has_xyz[1] && L.has_xyz[2]))
    throw InputError(path, "element vertex needs float properties x, y and z");
  if (L.faces > 0) throw InputError(path, "a range-grid PLY must not have faces");
  // PCL sizes its vertex buffer by the grid and asserts (aborts) past it.
  if (L.vertices > L.grid_cells)
    throw InputError(path, "element vertex has " + std::to_string(L.vertices) +
                               " vertices, more than the " + std::to_string(L.grid_cells) +
                               " range_grid cells they belong to");
  if (L.grid_properties != 1)
    throw InputError(path, "element range_grid needs 'property list uchar int vertex_indices'");
  return L;
}

// PCL applies the grid only when it has more cells than vertices; with as many,
// it returns the vertices in file order, right only if cell c names vertex c.
void check_cell_order(const std::string& path, const PlyLayout& L, std::size_t cell,
                      long long count, long long first_index) {
  if (L.vertices == L.grid_cells && (count == 0 || first_index != (long long)cell))
    throw InputError(path, "range_grid cell " + std::to_string(cell) + " does not name vertex " +
                               std::to_string(cell) + "; with as many vertices as cells, PCL's "
                               "reader would ignore the grid, so each cell must name its own");
}

// PCL silently turns an unparsable ASCII vertex into a hole, so the body is
// checked here first: every vertex line must hold its properties as numbers.
void check_ascii_body(const std::string& path, std::ifstream& in, const PlyLayout& L) {
  std::string line;
  for (std::size_t v = 0; v < L.vertices; ++v) {
    std::size_t line_no = L.header_lines + 1 + v;
    if (!std::getline(in, line))
      throw InputError(path, "file ends at vertex " + std::to_string(v) + " of " +
                                 std::to_string(L.vertices) + " (truncated)");
    const char* s = line.c_str();
    for (std::size_t k = 0; k < L.vertex_properties; ++k) {
      char* end = nullptr;
      double value = std::strtod(s, &end);
      if (end == s || !std::isfinite(value))
        throw InputError(path, "line " + std::to_string(line_no) + ": vertex " +
                                   std::to_string(v) + " needs " +
                                   std::to_string(L.vertex_properties) +
                                   " finite numbers, got '" + line + "'");
      s = end;
    }
  }
  for (std::size_t c = 0; c < L.grid_cells; ++c) {
    std::size_t line_no = L.header_lines + 1 + L.vertices + c;
    if (!std::getline(in, line))
      throw InputError(path, "file ends at range_grid cell " + std::to_string(c) + " of " +
                                 std::to_string(L.grid_cells) + " (truncated)");
    std::istringstream ls(line);
    long count = -1;
    if (!(ls >> count) || count < 0 || count > 255)
      throw InputError(path, "line " + std::to_string(line_no) + ": range_grid cell " +
                                 std::to_string(c) + " must start with an index count");
    long long first = -1;
    for (long k = 0; k < count; ++k) {
      long long index = -1;
      if (!(ls >> index) || index < 0 || std::size_t(index) >= L.vertices)
        throw InputError(path, "line " + std::to_string(line_no) + ": range_grid cell " +
                                   std::to_string(c) + " has a vertex index outside [0, " +
                                   std::to_string(L.vertices) + ")");
      if (k == 0) first = index;
    }
    check_cell_order(path, L, c, count, first);
  }
}

void check_binary_size(const std::string& path, const PlyLayout& L) {
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path, "cannot tell the file's size: " + ec.message());
  // Every cell holds at least its count byte; every vertex is referenced once.
  // The counts come from the header: compare by division first, as a product
  // can wrap (2^62 vertices x 12 bytes is 0) and PCL asserts on such counts.
  const std::uintmax_t body = size > L.header_bytes ? size - L.header_bytes : 0;
  if (L.vertex_stride == 0 || L.vertices > body / L.vertex_stride || L.grid_cells > body)
    throw InputError(path, "file has " + std::to_string(size) + " bytes, too few for the header's " +
                               std::to_string(L.vertices) + " vertices and " +
                               std::to_string(L.grid_cells) + " range_grid cells (truncated)");
  std::uintmax_t minimum = L.header_bytes + L.vertices * L.vertex_stride + L.grid_cells;
  if (size < minimum)
    throw InputError(path, "file has " + std::to_string(size) + " bytes, the header needs at least " +
                               std::to_string(minimum) + " (truncated)");
}

// PCL bounds a cell's vertex index only from above, as a signed product with
// the point size: a negative index reads before its buffer and the index
// one past the last vertex reads past it. The binary body is checked here
// first, like the ASCII one.
void check_binary_grid(const std::string& path, const PlyLayout& L) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(std::streamoff(L.header_bytes + L.vertices * L.vertex_stride));
  const std::vector<char> data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const bool big_endian = L.format == PlyHeader::Format::binary_be;
  std::size_t at = 0;
  // Reads `size` bytes as a two's-complement integer; false at the end of the data.
  auto next = [&](std::size_t size, bool is_signed, long long& value) {
    if (data.size() - at < size) return false;
    std::uint64_t u = 0;
    for (std::size_t k = 0; k < size; ++k) {
      const std::uint8_t byte = std::uint8_t(data[at + (big_endian ? k : size - 1 - k)]);
      u = (u << 8) | byte;
    }
    at += size;
    if (is_signed && size < 8 && (u >> (8 * size - 1)) != 0) u |= ~std::uint64_t(0) << (8 * size);
    value = static_cast<long long>(u);
    return true;
  };
  for (std::size_t c = 0; c < L.grid_cells; ++c) {
    long long count = 0;
    if (!next(L.grid_count_size, L.grid_count_signed, count))
      throw InputError(path, "file ends at range_grid cell " + std::to_string(c) + " of " +
                                 std::to_string(L.grid_cells) + " (truncated)");
    if (count < 0 || count > 255)
      throw InputError(path, "range_grid cell " + std::to_string(c) + " has " +
                                 std::to_string(count) + " vertex indices, expected 0 to 255");
    long long first = -1;
    for (long long k = 0; k < count; ++k) {
      long long index = -1;
      if (!next(4, true, index))
        throw InputError(path, "file ends at range_grid cell " + std::to_string(c) + " of " +
                                   std::to_string(L.grid_cells) + " (truncated)");
      if (index < 0 || std::size_t(index) >= L.vertices)
        throw InputError(path, "range_grid cell " + std::to_string(c) +
                                   " has a vertex index outside [0, " +
                                   std::to_string(L.vertices) + ")");
      if (k == 0) first = index;
    }
    check_cell_order(path, L, c, count, first);
  }
}

const pcl::PCLPointField* find_field(const pcl::PCLPointCloud2& c, const char* name) {
  for (const auto& f : c.fields)
    if (f.name == name) return &f;
  return nullptr;
}

float read_float(const pcl::PCLPointCloud2& c, std::size_t i, const pcl::PCLPointField& f) {
  float v;
  std::memcpy(&v, &c.data[i * c.point_step + f.offset], sizeof v);
  return v;
}

// Packed colour properties are PCL's to unpack; everything else a binary file
// holds is decoded directly, which PCL's reader (a callback and a vector per
// grid cell) does several times slower.
bool needs_pcl(const PlyLayout& L) {
  for (const std::string& name : L.vertex_names)
    if (name == "rgb" || name == "rgba") return true;
  return false;
}

// A grid of L's size with every cell a hole, and the attributes the file has.
RangeImage empty_image(const std::string& path, const PlyLayout& L, bool confidence, bool colors) {
  RangeImage image;
  image.cols = int(L.cols);
  image.rows = int(L.rows);
  image.source = path;
  const std::size_t n = std::size_t(L.cols) * std::size_t(L.rows);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  image.points.assign(n, Vec3f(nan, nan, nan));
  if (confidence) image.confidence.assign(n, 0.f);
  if (colors) image.colors.assign(n, Rgb{0, 0, 0});
  return image;
}

// A binary range grid whose header and grid check_binary_* accepted: cell c
// takes the vertex its first index names, NaN for an empty cell.
RangeImage decode_binary(const std::string& path, const PlyLayout& L) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(std::streamoff(L.header_bytes));
  std::vector<char> body((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const bool swap = L.format == PlyHeader::Format::binary_be;
  auto scalar = [&](std::size_t at, std::size_t size, char* out) {
    for (std::size_t k = 0; k < size; ++k) out[k] = body[at + (swap ? size - 1 - k : k)];
  };
  // Offsets of the properties read: x, y, z, confidence, red, green, blue.
  static const char* kNames[7] = {"x", "y", "z", "confidence", "red", "green", "blue"};
  long offset[7] = {-1, -1, -1, -1, -1, -1, -1};
  std::size_t at = 0;
  for (std::size_t k = 0; k < L.vertex_names.size(); ++k) {
    for (int r = 0; r < 7; ++r)
      if (L.vertex_names[k] == kNames[r] &&
          (r < 4 ? L.vertex_types[k] == "float" || L.vertex_types[k] == "float32"
                 : ply_scalar_size(L.vertex_types[k]) == 1))
        offset[r] = long(at);
    at += ply_scalar_size(L.vertex_types[k]);
  }
  const bool colors = offset[4] >= 0 && offset[5] >= 0 && offset[6] >= 0;
  RangeImage image = empty_image(path, L, offset[3] >= 0, colors);
  const std::size_t n = image.points.size();
  std::size_t cursor = L.vertices * L.vertex_stride;
  for (std::size_t c = 0; c < n; ++c) {
    std::int64_t count = 0;
    char bytes[8] = {0};
    scalar(cursor, L.grid_count_size, bytes);
    if (L.grid_count_size == 1) count = L.grid_count_signed ? std::int8_t(bytes[0]) : std::uint8_t(bytes[0]);
    else std::memcpy(&count, bytes, L.grid_count_size);  // checked: 0 to 255, so sign does not matter
    cursor += L.grid_count_size;
    if (count > 0) {
      std::int32_t index;
      scalar(cursor, 4, reinterpret_cast<char*>(&index));
      const std::size_t v = std::size_t(index) * L.vertex_stride;
      Vec3f p;
      for (int a = 0; a < 3; ++a) scalar(v + std::size_t(offset[a]), 4, reinterpret_cast<char*>(&p[a]));
      if (p.allFinite()) image.points[c] = p;
      if (offset[3] >= 0) scalar(v + std::size_t(offset[3]), 4, reinterpret_cast<char*>(&image.confidence[c]));
      if (colors)
        for (int ch = 0; ch < 3; ++ch) image.colors[c][ch] = std::uint8_t(body[v + std::size_t(offset[4 + ch])]);
    }
    cursor += std::size_t(count) * 4;
  }
  return image;
}

// A number as strtod reads it (blanks first, an optional '+'), to the
// type's precision. A float out of float's range (1e-50, 1e39) is read as
// a double and narrowed, as PCL's reader did, not refused.
bool ascii_number(const char*& s, const char* stop, bool as_float, double* out) {
  while (s < stop && (*s == ' ' || *s == '\t')) ++s;
  if (s < stop && *s == '+') ++s;
  if (as_float) {
    float f = 0;
    const std::from_chars_result r = std::from_chars(s, stop, f);
    if (r.ec == std::errc() && r.ptr != s) {
      s = r.ptr;
      *out = f;
      return std::isfinite(f);
    }
    if (r.ec != std::errc::result_out_of_range) return false;
  }
  double wide = 0;
  const std::from_chars_result r = std::from_chars(s, stop, wide);
  if (r.ec != std::errc() || r.ptr == s || !std::isfinite(wide)) return false;
  s = r.ptr;
  *out = as_float ? double(float(wide)) : wide;
  return true;
}

bool ascii_integer(const char*& s, const char* stop, long long* out) {
  while (s < stop && (*s == ' ' || *s == '\t')) ++s;
  if (s < stop && *s == '+') ++s;
  const std::from_chars_result r = std::from_chars(s, stop, *out);
  if (r.ec != std::errc() || r.ptr == s) return false;
  s = r.ptr;
  return true;
}

// An ASCII range grid without packed colours, parsed once with
// std::from_chars on all cores (acquisition/text_records.h) and checked as
// it goes (check_ascii_body's complaints), then laid out as decode_binary
// does: the vertex lines first, then the cells that name them. PCL's reader
// parsed the body again through streams: the bunny's ten ASCII scans took 1.4 s.
RangeImage decode_ascii(const std::string& path, const PlyLayout& L) {
  const std::string body = read_file_from(path, L.header_bytes);
  // Every vertex and cell takes a line, of a byte at least: the header's
  // counts must fit before the grid is sized by them.
  if (std::uint64_t(L.vertices) + std::uint64_t(L.grid_cells) > body.size() + 1)
    throw InputError(path, "the body has " + std::to_string(body.size()) + " bytes, too few for the header's " +
                               std::to_string(L.vertices) + " vertices and " + std::to_string(L.grid_cells) +
                               " range_grid cells (truncated)");
  auto every_line = [](std::string_view) { return true; };
  // What each property is to the image: x, y, z (float: read_layout), confidence (any scalar, as PCL
  // read it), red, green, blue (one byte each).
  static const char* kNames[7] = {"x", "y", "z", "confidence", "red", "green", "blue"};
  std::vector<int> role(L.vertex_properties, -1);
  std::vector<std::uint8_t> single(L.vertex_properties, 0);
  bool has[7] = {};
  for (std::size_t k = 0; k < L.vertex_properties; ++k) {
    const std::string& type = L.vertex_types[k];
    single[k] = type == "float" || type == "float32";
    for (int r = 0; r < 7; ++r)
      if (L.vertex_names[k] == kNames[r] &&
          (r < 3 ? single[k] != 0 : r == 3 ? ply_scalar_size(type) > 0 : ply_scalar_size(type) == 1))
        role[k] = r, has[r] = true;
  }
  const bool colors = has[4] && has[5] && has[6];
  std::vector<float> values(L.vertices * 4, 0.f);
  std::vector<Rgb> vertex_colors(colors ? L.vertices : 0);
  const std::vector<TextBlock> vertex_lines = cut_records(body, L.header_lines + 1, L.vertices, every_line);
  parse_records(vertex_lines, every_line, [&](std::string_view line, std::size_t line_no, std::size_t v) {
    const char* s = line.data();
    const char* const stop = line.data() + line.size();
    for (std::size_t k = 0; k < L.vertex_properties; ++k) {
      double value = 0;
      if (!ascii_number(s, stop, single[k] != 0, &value))
        throw InputError(path, "line " + std::to_string(line_no) + ": vertex " + std::to_string(v) + " needs " +
                                   std::to_string(L.vertex_properties) + " finite numbers, got '" + std::string(line) +
                                   "'");
      if (role[k] >= 4) vertex_colors[v][std::size_t(role[k] - 4)] = std::uint8_t(std::clamp(value, 0.0, 255.0));
      else if (role[k] >= 0) values[4 * v + std::size_t(role[k])] = float(value);
    }
  });
  if (record_count(vertex_lines) < L.vertices)
    throw InputError(path, "file ends at vertex " + std::to_string(record_count(vertex_lines)) + " of " +
                               std::to_string(L.vertices) + " (truncated)");
  const std::size_t cells_at =
      vertex_lines.empty() ? 0 : std::size_t(vertex_lines.back().text.data() + vertex_lines.back().text.size() - body.data());
  RangeImage image = empty_image(path, L, has[3], colors);
  const std::size_t n = image.points.size();
  const std::vector<TextBlock> cell_lines =
      cut_records(std::string_view(body).substr(cells_at), L.header_lines + 1 + L.vertices, L.grid_cells, every_line);
  parse_records(cell_lines, every_line, [&](std::string_view line, std::size_t line_no, std::size_t c) {
    const char* s = line.data();
    const char* const stop = line.data() + line.size();
    long long count = -1;
    if (!ascii_integer(s, stop, &count) || count < 0 || count > 255)
      throw InputError(path, "line " + std::to_string(line_no) + ": range_grid cell " + std::to_string(c) +
                                 " must start with an index count");
    long long first = -1;
    for (long long k = 0; k < count; ++k) {
      long long index = -1;
      if (!ascii_integer(s, stop, &index) || index < 0 || std::size_t(index) >= L.vertices)
        throw InputError(path, "line " + std::to_string(line_no) + ": range_grid cell " + std::to_string(c) +
                                   " has a vertex index outside [0, " + std::to_string(L.vertices) + ")");
      if (k == 0) first = index;
    }
    check_cell_order(path, L, c, count, first);
    if (count == 0 || c >= n) return;
    const float* f = &values[4 * std::size_t(first)];
    const Vec3f point(f[0], f[1], f[2]);
    if (point.allFinite()) image.points[c] = point;
    if (has[3]) image.confidence[c] = f[3];
    if (colors) image.colors[c] = vertex_colors[std::size_t(first)];
  });
  if (record_count(cell_lines) < L.grid_cells)
    throw InputError(path, "file ends at range_grid cell " + std::to_string(record_count(cell_lines)) + " of " +
                               std::to_string(L.grid_cells) + " (truncated)");
  return image;
}

RangeImage read_range_grid(const std::string& path, std::string* warning) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file");
  PlyLayout L = read_layout(path, in);
  *warning = L.warning;
  if (L.format == PlyHeader::Format::ascii && !needs_pcl(L)) return decode_ascii(path, L);
  if (L.format == PlyHeader::Format::ascii) check_ascii_body(path, in, L);
  in.close();
  if (L.format != PlyHeader::Format::ascii) {
    check_binary_size(path, L);
    check_binary_grid(path, L);
  }

  if (L.format != PlyHeader::Format::ascii && !needs_pcl(L)) return decode_binary(path, L);

  pcl::PCLPointCloud2 cloud;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int ply_version = 0;
  pcl::PLYReader reader;
  if (reader.read(path, cloud, origin, orientation, ply_version, 0) < 0)
    throw InputError(path, "PCL could not parse the PLY body (truncated or corrupt range_grid)");
  if (long(cloud.width) != L.cols || long(cloud.height) != L.rows)
    throw InputError(path, "range grid came back as " + std::to_string(cloud.width) + "x" +
                               std::to_string(cloud.height) + ", expected " +
                               std::to_string(L.cols) + "x" + std::to_string(L.rows));

  const auto* fx = find_field(cloud, "x");
  const auto* fy = find_field(cloud, "y");
  const auto* fz = find_field(cloud, "z");
  const auto* fconf = find_field(cloud, "confidence");
  const auto* frgb = find_field(cloud, "rgb");
  if (!frgb) frgb = find_field(cloud, "rgba");
  if (!fx || !fy || !fz) throw InputError(path, "vertex has no x, y, z");

  RangeImage image;
  image.cols = int(L.cols);
  image.rows = int(L.rows);
  image.source = path;
  const std::size_t n = std::size_t(L.cols) * std::size_t(L.rows);
  image.points.resize(n);
  if (fconf) image.confidence.resize(n, 0.f);
  if (frgb) image.colors.resize(n, Rgb{0, 0, 0});
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < n; ++i) {
    Vec3f p(read_float(cloud, i, *fx), read_float(cloud, i, *fy), read_float(cloud, i, *fz));
    image.points[i] = p.allFinite() ? p : Vec3f(nan, nan, nan);
    if (fconf) image.confidence[i] = read_float(cloud, i, *fconf);
    if (frgb) {
      std::uint32_t packed;
      std::memcpy(&packed, &cloud.data[i * cloud.point_step + frgb->offset], 4);
      image.colors[i] = Rgb{std::uint8_t(packed >> 16), std::uint8_t(packed >> 8),
                            std::uint8_t(packed)};
    }
  }
  return image;
}

}  // namespace

RangeImage read_range_grid_ply(const std::string& path) {
  std::string warning;
  RangeImage image = read_range_grid(path, &warning);
  if (!warning.empty()) image.warnings.push_back(warning);
  return image;
}

void write_range_grid_ply(const std::string& path, const RangeImage& image) {
  const std::size_t n = std::size_t(image.cols) * std::size_t(image.rows);
  if (image.cols <= 0 || image.rows <= 0 || image.points.size() != n)
    throw InputError(path, "range image to write has " + std::to_string(image.points.size()) +
                               " samples, expected cols*rows");
  pcl::PCLPointCloud2 cloud;
  cloud.width = std::uint32_t(image.cols);
  cloud.height = std::uint32_t(image.rows);
  cloud.is_dense = false;
  auto add_field = [&](const char* name, std::uint8_t type) {
    pcl::PCLPointField f;
    f.name = name;
    f.offset = cloud.point_step;
    f.datatype = type;
    f.count = 1;
    cloud.fields.push_back(f);
    cloud.point_step += 4;
  };
  add_field("x", pcl::PCLPointField::FLOAT32);
  add_field("y", pcl::PCLPointField::FLOAT32);
  add_field("z", pcl::PCLPointField::FLOAT32);
  const bool colors = image.colors.size() == n;
  const bool confidence = image.confidence.size() == n;
  if (confidence) add_field("confidence", pcl::PCLPointField::FLOAT32);
  if (colors) add_field("rgb", pcl::PCLPointField::FLOAT32);
  cloud.row_step = cloud.point_step * cloud.width;
  cloud.data.resize(std::size_t(cloud.row_step) * cloud.height);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint8_t* dst = &cloud.data[i * cloud.point_step];
    std::memcpy(dst, image.points[i].data(), 12);
    std::size_t off = 12;
    if (confidence) std::memcpy(dst + off, &image.confidence[i], 4), off += 4;
    if (colors) {
      const Rgb& c = image.colors[i];
      std::uint32_t packed = (std::uint32_t(c[0]) << 16) | (std::uint32_t(c[1]) << 8) | c[2];
      std::memcpy(dst + off, &packed, 4);
    }
  }
  write_atomically(path, [&](const std::string& tmp) {
    pcl::PLYWriter writer;
    if (writer.writeBinary(tmp, cloud, Eigen::Vector4f::Zero(), Eigen::Quaternionf::Identity(),
                           /*use_camera=*/false) < 0)
      throw InputError(path, "PCL could not write the range-grid PLY");
  });
}

std::vector<ConfEntry> read_conf(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open file");
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  std::vector<ConfEntry> entries;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    std::istringstream ls(line);
    std::string key;
    if (!(ls >> key) || key != "bmesh") continue;  // camera, comments, blank lines
    std::string file;
    float t[3], q[4];
    if (!(ls >> file >> t[0] >> t[1] >> t[2] >> q[0] >> q[1] >> q[2] >> q[3]))
      throw InputError(path, "line " + std::to_string(n) +
                                 ": expected 'bmesh FILE tx ty tz qi qj qk qr'");
    Eigen::Quaternionf quat(q[3], q[0], q[1], q[2]);  // Eigen's order is (w, x, y, z)
    if (!(std::abs(quat.norm() - 1.f) < 1e-2f))
      throw InputError(path, "line " + std::to_string(n) + ": quaternion is not unit length");
    ConfEntry e;
    e.file = (folder / file).string();
    e.pose.rotation = quat.normalized().toRotationMatrix().transpose();
    e.pose.translation = Vec3f(t[0], t[1], t[2]);
    std::error_code ec;  // e.g. a name too long for the file system: not found either
    if (!std::filesystem::exists(e.file, ec))
      throw InputError(path, "line " + std::to_string(n) + ": scan '" + file +
                                 "' does not exist (looked for " + e.file + ")");
    entries.push_back(std::move(e));
  }
  if (entries.empty()) throw InputError(path, "no 'bmesh' lines: not a scan .conf");
  return entries;
}

void write_conf(const std::string& path, const std::vector<ConfEntry>& entries) {
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  write_atomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp);
    out.precision(9);
    for (const ConfEntry& e : entries) {
      // Stored as the conjugate: R(q)^T is the scan-to-world rotation.
      Eigen::Quaternionf q(Eigen::Matrix3f(e.pose.rotation.transpose()));
      q.normalize();
      std::string file = std::filesystem::path(e.file).lexically_proximate(folder).string();
      out << "bmesh " << file << ' ' << e.pose.translation.x() << ' ' << e.pose.translation.y()
          << ' ' << e.pose.translation.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z()
          << ' ' << q.w() << '\n';
    }
    if (!out) throw InputError(path, "write failed");
  });
}

}  // namespace scan2lod
