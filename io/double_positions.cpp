#include <scan2lod/io/double_positions.h>

#include <scan2lod/core/error.h>
#include <scan2lod/io/line_writer.h>
#include <scan2lod/io/ply_header.h>

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>

namespace scan2lod {
namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the PLY writer lays values out as they lie in memory");

using File = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;

File create(const std::string& file, const std::string& name) {
  File f(std::fopen(file.c_str(), "wb"), &std::fclose);
  if (!f) throw InputError(name, "cannot create the file (does the folder exist?)");
  return f;
}

// ---------------------------------------------------------------------------
// Reading a PLY's positions, by the layout its header (io/ply_header.h) gives.

// One binary value of PLY type `t` at `p`, as a double.
double binary_value(const char* p, const std::string& t, bool swap) {
  char b[8];
  const std::size_t n = ply_scalar_size(t);
  std::memcpy(b, p, n);
  if (swap) std::reverse(b, b + n);
  auto as = [&](auto v) {
    std::memcpy(&v, b, sizeof v);
    return double(v);
  };
  if (t == "char" || t == "int8") return as(std::int8_t());
  if (t == "uchar" || t == "uint8") return as(std::uint8_t());
  if (t == "short" || t == "int16") return as(std::int16_t());
  if (t == "ushort" || t == "uint16") return as(std::uint16_t());
  if (t == "int" || t == "int32") return as(std::int32_t());
  if (t == "uint" || t == "uint32") return as(std::uint32_t());
  if (t == "double" || t == "float64") return as(double());
  return as(float());
}

std::vector<Vec3d> binary_positions(const std::string& path, std::ifstream& in, const PlyHeader& layout,
                                    std::size_t vertex, const int (&xyz)[3]) {
  std::uint64_t skip = 0;
  for (std::size_t e = 0; e < vertex; ++e) {
    std::uint64_t record = 0;
    for (const PlyProperty& p : layout.elements[e].properties) record += std::uint64_t(ply_scalar_size(p.type));
    skip += record * layout.elements[e].count;
  }
  const PlyElement& v = layout.elements[vertex];
  std::vector<std::size_t> offset(v.properties.size() + 1, 0);
  for (std::size_t i = 0; i < v.properties.size(); ++i) offset[i + 1] = offset[i] + ply_scalar_size(v.properties[i].type);
  const std::size_t record = offset.back();
  const bool swap = layout.format == PlyHeader::Format::binary_be;
  in.seekg(std::streamoff(layout.bytes + skip));
  std::vector<Vec3d> positions(v.count);
  std::vector<char> block(record * 65536);
  for (std::size_t first = 0; first < v.count; first += 65536) {
    const std::size_t n = std::min<std::size_t>(65536, v.count - first);
    if (!in.read(block.data(), std::streamsize(n * record)))
      throw InputError(path, "ends inside vertex " + std::to_string(first + std::size_t(in.gcount()) / record) +
                                 " of " + std::to_string(v.count));
    for (std::size_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) {
        const std::size_t p = std::size_t(xyz[k]);
        positions[first + i][k] = binary_value(block.data() + i * record + offset[p], v.properties[p].type, swap);
      }
  }
  return positions;
}

std::vector<Vec3d> ascii_positions(const std::string& path, std::ifstream& in, const PlyHeader& layout,
                                   std::size_t vertex, const int (&xyz)[3]) {
  in.seekg(std::streamoff(layout.bytes));
  std::string word;
  for (std::size_t e = 0; e < vertex; ++e)
    for (std::size_t i = 0; i < layout.elements[e].count * layout.elements[e].properties.size(); ++i) in >> word;
  const PlyElement& v = layout.elements[vertex];
  std::vector<Vec3d> positions(v.count);
  for (std::size_t i = 0; i < v.count; ++i)
    for (std::size_t p = 0; p < v.properties.size(); ++p) {
      if (!(in >> word)) throw InputError(path, "ends inside vertex " + std::to_string(i) + " of " + std::to_string(v.count));
      for (int k = 0; k < 3; ++k) {
        if (std::size_t(xyz[k]) != p) continue;
        double value = 0;
        const auto r = std::from_chars(word.data(), word.data() + word.size(), value);
        if (r.ec != std::errc() || r.ptr != word.data() + word.size())
          throw InputError(path, "vertex " + std::to_string(i) + ": " + v.properties[p].name + " '" + word +
                                     "' is not a number");
        positions[i][k] = value;
      }
    }
  return positions;
}

}  // namespace

void write_ply_in_frame(const std::string& file, const std::string& name, const TriangleMesh& mesh,
                        const Vec3d& origin) {
  const File f = create(file, name);
  const bool has_n = !mesh.normals.empty(), has_c = !mesh.colors.empty();
  std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(mesh.positions.size()) +
                       "\nproperty double x\nproperty double y\nproperty double z\n";
  if (has_n) header += "property float nx\nproperty float ny\nproperty float nz\n";
  if (has_c) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  header += "element face " + std::to_string(mesh.triangles.size()) +
            "\nproperty list uchar int vertex_indices\nend_header\n";
  bool failed = std::fwrite(header.data(), 1, header.size(), f.get()) != header.size();
  {
    LineWriter out(f.get());
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
      for (int k = 0; k < 3; ++k) out.put(origin[k] + double(mesh.positions[i][k]));
      if (has_n) out.put(mesh.normals[i]);
      if (has_c) out.put(mesh.colors[i]);
      out.end_record();
    }
    for (const Triangle& t : mesh.triangles) {
      out.put(std::uint8_t(3));
      out.put(t);
      out.end_record();
    }
    out.flush();
    failed |= out.failed();
  }
  if (failed || std::fflush(f.get()) != 0) throw InputError(name, "writing ply failed (disk full?)");
}

void write_off_in_frame(const std::string& file, const std::string& name, const TriangleMesh& mesh,
                        const Vec3d& origin) {
  const File f = create(file, name);
  const bool has_n = !mesh.normals.empty(), has_c = !mesh.colors.empty();
  bool failed;
  {
    LineWriter out(f.get());
    out.text(has_c ? (has_n ? "CNOFF" : "COFF") : (has_n ? "NOFF" : "OFF"));
    out.end_line();
    out.number((long long)mesh.positions.size());
    out.text(" ");
    out.number((long long)mesh.triangles.size());
    out.text(" 0");
    out.end_line();
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        if (k) out.text(" ");
        out.number(origin[k] + double(mesh.positions[i][k]));
      }
      for (int k = 0; has_n && k < 3; ++k) out.text(" "), out.number(mesh.normals[i][k]);
      // RGBA, as OpenMesh writes it: readers such as Open3D's take COFF colours as four values.
      for (int k = 0; has_c && k < 3; ++k) out.text(" "), out.number((long long)mesh.colors[i][k]);
      if (has_c) out.text(" 255");
      out.end_line();
    }
    for (const Triangle& t : mesh.triangles) {
      out.text("3");
      for (int k = 0; k < 3; ++k) out.text(" "), out.number((long long)t[k]);
      out.end_line();
    }
    out.flush();
    failed = out.failed();
  }
  if (failed || std::fflush(f.get()) != 0) throw InputError(name, "writing off failed (disk full?)");
}

std::vector<Vec3d> read_ply_double_positions(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open the file for reading");
  // No limit on its lines: read_mesh's checks found its end_header.
  const PlyHeader layout = parse_ply_header(in, std::numeric_limits<std::size_t>::max());
  if (!layout.ended) throw InputError(path, "PLY header has no end_header line");
  std::size_t vertex = 0;
  while (vertex < layout.elements.size() && layout.elements[vertex].name != "vertex") ++vertex;
  if (vertex == layout.elements.size()) throw InputError(path, "PLY has no element vertex");
  int xyz[3] = {-1, -1, -1};
  bool wide = false;
  const std::vector<PlyProperty>& properties = layout.elements[vertex].properties;
  for (std::size_t p = 0; p < properties.size(); ++p)
    for (int k = 0; k < 3; ++k)
      if (properties[p].name == std::string(1, char('x' + k))) {
        xyz[k] = int(p);
        wide |= ply_scalar_size(properties[p].type) == 8;
      }
  if (!wide) return {};
  if (std::min({xyz[0], xyz[1], xyz[2]}) < 0) throw InputError(path, "PLY element vertex needs properties x, y and z");
  for (std::size_t e = 0; e <= vertex; ++e)
    for (const PlyProperty& p : layout.elements[e].properties)
      if (p.type == "list")
        throw InputError(path, "PLY element " + layout.elements[e].name + " has a list property '" + p.name +
                                   "'; only face vertex_indices may be a list");
  return layout.format == PlyHeader::Format::ascii ? ascii_positions(path, in, layout, vertex, xyz)
                                                   : binary_positions(path, in, layout, vertex, xyz);
}

std::vector<Vec3d> read_off_double_positions(const std::string& path, std::size_t vertices) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open the file for reading");
  std::string line;
  std::getline(in, line);
  if (line.find("BINARY") != std::string::npos) return {};
  std::size_t number = 1;
  auto next_line = [&]() {
    while (std::getline(in, line)) {
      ++number;
      const std::size_t start = line.find_first_not_of(" \t\r");
      if (start != std::string::npos && line[start] != '#') return true;
    }
    return false;
  };
  if (!next_line()) throw InputError(path, "OFF header: missing vertex/face/edge counts");
  std::vector<Vec3d> positions(vertices);
  for (std::size_t i = 0; i < vertices; ++i) {
    if (!next_line()) throw InputError(path, "ends before vertex " + std::to_string(i) + " of " + std::to_string(vertices));
    const char* p = line.data();
    const char* end = p + line.size();
    for (int k = 0; k < 3; ++k) {
      while (p < end && (*p == ' ' || *p == '\t')) ++p;
      const auto r = std::from_chars(p, end, positions[i][k]);
      if (r.ec != std::errc())
        throw InputError(path, "line " + std::to_string(number) + ": vertex " + std::to_string(i) +
                                   " needs three numbers x y z first");
      p = r.ptr;
    }
  }
  return positions;
}

}  // namespace scan2lod
