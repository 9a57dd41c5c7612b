#include "acquisition/range_grid_ply.h"

#include "core/error.h"
#include "io/atomic_file.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/ply_io.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

namespace scan2lod {
namespace {

struct PlyLayout {
  enum class Format { ascii, binary_le, binary_be } format = Format::ascii;
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
};

std::size_t type_size(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" ||
      t == "float32")
    return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

// The header is parsed here, not left to PCL, so that every complaint names the
// file and the line; PCL reports most problems only as "parse error".
PlyLayout read_layout(const std::string& path, std::ifstream& in) {
  PlyLayout L;
  std::string line;
  if (!std::getline(in, line) || line.rfind("ply", 0) != 0)
    throw InputError(path, "not a PLY file (the first line must be 'ply')");
  L.header_bytes = line.size() + 1;
  std::string element;
  bool ended = false;
  for (std::size_t n = 2; std::getline(in, line); ++n) {
    L.header_bytes += line.size() + 1;
    L.header_lines = n;
    if (n > 10000) throw InputError(path, "PLY header has no 'end_header' in 10000 lines");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    auto fail = [&](const std::string& what) {
      throw InputError(path, "header line " + std::to_string(n) + " ('" + line + "'): " + what);
    };
    if (key == "format") {
      std::string f;
      ls >> f;
      if (f == "ascii") L.format = PlyLayout::Format::ascii;
      else if (f == "binary_little_endian") L.format = PlyLayout::Format::binary_le;
      else if (f == "binary_big_endian") L.format = PlyLayout::Format::binary_be;
      else fail("expected ascii, binary_little_endian or binary_big_endian");
    } else if (key == "obj_info") {
      std::string name;
      long value = -1;
      ls >> name;
      if (name == "num_cols" || name == "num_rows") {
        if (!(ls >> value) || value <= 0 || value > 100000) fail("expected a positive size");
        (name == "num_cols" ? L.cols : L.rows) = value;
      }
    } else if (key == "element") {
      long long count = -1;
      ls >> element >> count;
      if (count < 0) fail("expected 'element NAME COUNT' with COUNT >= 0");
      if (element == "vertex") L.vertices = std::size_t(count);
      else if (element == "range_grid") L.grid_cells = std::size_t(count), L.has_grid = true;
      else if (element == "face") L.faces = std::size_t(count);
      else if (count > 0) fail("unexpected element '" + element + "' in a range-grid PLY");
    } else if (key == "property") {
      std::string type, name;
      ls >> type;
      if (element == "vertex") {
        if (type == "list") fail("vertex properties must be scalars");
        ls >> name;
        std::size_t size = type_size(type);
        if (size == 0) fail("unknown property type '" + type + "'");
        ++L.vertex_properties;
        L.vertex_stride += size;
        if (name == "x" || name == "y" || name == "z") {
          if (type != "float" && type != "float32") fail("x, y, z must be float");
          L.has_xyz[name[0] - 'x'] = true;
        }
      } else if (element == "range_grid") {
        std::string count_type, index_type;
        ls >> count_type >> index_type;
        if (type != "list" || type_size(count_type) == 0 || type_size(index_type) != 4)
          fail("range_grid must be 'property list uchar int vertex_indices'");
      }
    } else if (key == "end_header") {
      ended = true;
      break;
    }
  }
  if (!ended) throw InputError(path, "PLY header ends before 'end_header'");
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
  return L;
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
    for (long k = 0; k < count; ++k) {
      long long index = -1;
      if (!(ls >> index) || index < 0 || std::size_t(index) >= L.vertices)
        throw InputError(path, "line " + std::to_string(line_no) + ": range_grid cell " +
                                   std::to_string(c) + " has a vertex index outside [0, " +
                                   std::to_string(L.vertices) + ")");
    }
  }
}

void check_binary_size(const std::string& path, const PlyLayout& L) {
  std::uintmax_t size = std::filesystem::file_size(path);
  // Every cell holds at least its count byte; every vertex is referenced once.
  std::uintmax_t minimum = L.header_bytes + L.vertices * L.vertex_stride + L.grid_cells;
  if (size < minimum)
    throw InputError(path, "file has " + std::to_string(size) + " bytes, the header needs at least " +
                               std::to_string(minimum) + " (truncated)");
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

}  // namespace

RangeImage read_range_grid_ply(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file");
  PlyLayout L = read_layout(path, in);
  if (L.format == PlyLayout::Format::ascii) check_ascii_body(path, in, L);
  else check_binary_size(path, L);
  in.close();

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
    if (!std::filesystem::exists(e.file))
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
