#include <scan2lod/acquisition/organized_pcd.h>

#include <scan2lod/acquisition/text_records.h>
#include <scan2lod/core/error.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/common/io.h>
#include <pcl/io/pcd_io.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

namespace scan2lod {
namespace {

// What the header promises, checked before PCL sees the file: PCL 1.13's
// reader crashes on a header without fields (it prints the field list of an
// empty cloud), allocates POINTS x point size before reading any data, keeps
// uninitialised sizes for unparsable numbers and trusts the sizes stored in
// compressed data. Nothing here is read by PCL unless it passed these checks.
struct PcdLayout {
  enum class Data { ascii, binary, compressed } data = Data::ascii;
  std::vector<std::string> names;
  std::vector<int> sizes, counts;
  std::vector<char> types;  // I, U or F per field
  double viewpoint[7] = {0, 0, 0, 1, 0, 0, 0};  // tx ty tz qw qx qy qz
  std::uint64_t width = 0, height = 0, points = 0;
  std::uint64_t point_step = 0, values_per_point = 0;
  std::uint64_t body_offset = 0;  // first byte after the DATA line
};

std::vector<std::string> split_blanks(const std::string& line) {
  std::vector<std::string> tokens;
  std::size_t at = 0;
  while ((at = line.find_first_not_of(" \t\r", at)) != std::string::npos) {
    const std::size_t end = line.find_first_of(" \t\r", at);
    tokens.push_back(line.substr(at, end - at));
    at = end;
  }
  return tokens;
}

// A header line as it may appear in a message: bounded and printable.
std::string shown(const std::string& line) {
  std::string s = line.substr(0, 60);
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  return line.size() > 60 ? s + "..." : s;
}

template <class T>
bool parse_whole(const std::string& token, T& value) {
  auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && end == token.data() + token.size();
}

bool parse_float(const std::string& token, double& value) {
  char* end = nullptr;
  value = std::strtod(token.c_str(), &end);
  return !token.empty() && end == token.c_str() + token.size();
}

PcdLayout read_pcd_layout(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file");
  PcdLayout L;
  // Rank of each keyword: FIELDS, SIZE, TYPE and COUNT must come in this
  // order and before POINTS, which PCL sizes its buffer by.
  enum { kFields = 1, kSize, kType, kCount, kPoints };
  int last_rank = 0;
  bool seen_width = false, seen_height = false, seen_viewpoint = false, seen_type = false,
       seen_data = false;
  std::string line;
  for (std::size_t n = 1; !seen_data && std::getline(in, line); ++n) {
    if (n > 1000) throw InputError(path, "PCD header has no DATA line in 1000 lines");
    if (line.empty()) continue;  // PCL skips these
    const std::vector<std::string> t = split_blanks(line);
    auto fail = [&](const std::string& what) {
      throw InputError(path, "header line " + std::to_string(n) + " ('" + shown(line) + "'): " + what);
    };
    // PCL ends its header at a line of blanks and reads the rest as data.
    if (t.empty()) fail("a header line of blanks only; expected a keyword");
    const std::string& key = t[0];
    const std::size_t values = t.size() - 1;
    auto ordered = [&](int rank) {
      if (rank <= last_rank)
        fail("out of order or repeated; expected FIELDS, SIZE, TYPE, [COUNT], then POINTS");
      last_rank = rank;
    };
    auto per_field = [&]() {
      if (values != L.names.size())
        fail("has " + std::to_string(values) + " values for " + std::to_string(L.names.size()) +
             " FIELDS");
    };
    if (key[0] == '#' || key == "VERSION") continue;
    if (key == "FIELDS" || key == "COLUMNS") {
      ordered(kFields);
      if (values == 0 || values > 10000) fail("expected 1 to 10000 field names");
      L.names.assign(t.begin() + 1, t.end());
      L.sizes.assign(values, 4);  // PCL's defaults when SIZE/TYPE/COUNT are missing
      L.counts.assign(values, 1);
    } else if (key == "SIZE") {
      ordered(kSize);
      per_field();
      for (std::size_t i = 0; i < values; ++i) {
        int size = 0;
        if (!parse_whole(t[i + 1], size) || (size != 1 && size != 2 && size != 4 && size != 8))
          fail("field '" + L.names[i] + "' has size '" + t[i + 1] + "'; expected 1, 2, 4 or 8");
        L.sizes[i] = size;
      }
    } else if (key == "TYPE") {
      ordered(kType);
      per_field();
      seen_type = true;
      L.types.assign(values, 'F');
      for (std::size_t i = 0; i < values; ++i) {
        const std::string& type = t[i + 1];
        const char c = type.size() == 1 ? char(std::toupper(static_cast<unsigned char>(type[0]))) : '?';
        if ((c != 'I' && c != 'U' && c != 'F') || (c == 'F' && L.sizes[i] != 4 && L.sizes[i] != 8))
          fail("field '" + L.names[i] + "' has type '" + type + "' for size " +
               std::to_string(L.sizes[i]) + "; expected I, U or F (F of size 4 or 8)");
        L.types[i] = c;
      }
    } else if (key == "COUNT") {
      ordered(kCount);
      per_field();
      for (std::size_t i = 0; i < values; ++i)
        if (!parse_whole(t[i + 1], L.counts[i]) || L.counts[i] < 1 || L.counts[i] > 100000)
          fail("field '" + L.names[i] + "' has count '" + t[i + 1] + "'; expected 1 to 100000");
    } else if (key == "WIDTH" || key == "HEIGHT") {
      bool& seen = key == "WIDTH" ? seen_width : seen_height;
      std::uint64_t& value = key == "WIDTH" ? L.width : L.height;
      if (seen) fail("repeated");
      seen = true;
      if (values != 1 || !parse_whole(t[1], value) || value > 0x7fffffffu)
        fail("expected one count below 2^31");
    } else if (key == "VIEWPOINT") {
      if (seen_viewpoint) fail("repeated");
      seen_viewpoint = true;
      double v[7];
      if (values != 7) fail("expected 7 numbers (tx ty tz qw qx qy qz)");
      for (int i = 0; i < 7; ++i)
        if (!parse_float(t[i + 1], v[i]) || !std::isfinite(v[i])) fail("expected 7 finite numbers");
      if (std::hypot(std::hypot(v[3], v[4]), std::hypot(v[5], v[6])) < 1e-6)
        fail("the orientation quaternion is zero");
      std::copy(v, v + 7, L.viewpoint);
    } else if (key == "POINTS") {
      ordered(kPoints);
      if (values != 1 || !parse_whole(t[1], L.points) || L.points > 0x7fffffffu)
        fail("expected one count below 2^31");
    } else if (key == "DATA") {
      if (values < 1) fail("expected ascii, binary or binary_compressed");
      if (t[1] == "ascii") L.data = PcdLayout::Data::ascii;
      else if (t[1] == "binary") L.data = PcdLayout::Data::binary;
      else if (t[1] == "binary_compressed") L.data = PcdLayout::Data::compressed;
      else fail("expected ascii, binary or binary_compressed");
      L.body_offset = std::uint64_t(in.tellg());
      seen_data = true;
    } else {
      fail("unknown keyword '" + shown(key) + "'");
    }
  }
  if (!seen_data) throw InputError(path, "PCD header ends before its DATA line");
  if (L.names.empty() || !seen_type || last_rank < kPoints)
    throw InputError(path, "PCD header needs FIELDS, SIZE, TYPE and POINTS lines");
  if (!seen_width || !seen_height) throw InputError(path, "PCD header needs WIDTH and HEIGHT lines");
  if (L.width * L.height != L.points)
    throw InputError(path, "PCD header: WIDTH " + std::to_string(L.width) + " x HEIGHT " +
                               std::to_string(L.height) + " differs from POINTS " +
                               std::to_string(L.points));
  if (L.points == 0) throw InputError(path, "the cloud is empty");
  for (std::size_t i = 0; i < L.names.size(); ++i) {
    L.point_step += std::uint64_t(L.sizes[i]) * std::uint64_t(L.counts[i]);
    L.values_per_point += std::uint64_t(L.counts[i]);
  }
  if (L.point_step > 0xffffffu) throw InputError(path, "PCD header: a point of more than 16 MB");

  // PCL goes on reading header lines after DATA until one is not a keyword;
  // data that starts like one would change the layout behind our back.
  for (int k = 0; k < 1000 && std::getline(in, line); ++k) {
    if (line.empty()) continue;
    std::string key;
    std::istringstream(line) >> key;
    if (key.rfind('#', 0) == 0 || key.rfind("VERSION", 0) == 0) continue;
    for (const char* keyword : {"FIELDS", "COLUMNS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT",
                                "VIEWPOINT", "POINTS", "DATA"})
      if (key.rfind(keyword, 0) == 0)
        throw InputError(path, "the data after the DATA line starts with a header keyword ('" +
                                   shown(line) + "')");
    break;
  }
  return L;
}

// A binary body must hold what the header promises before PCL allocates for
// it (ASCII bodies are read here: decode_ascii_pcd).
void check_pcd_body(const std::string& path, const PcdLayout& L) {
  std::error_code ec;
  const std::uint64_t size = std::filesystem::file_size(path, ec);
  const std::uint64_t body = ec || size < L.body_offset ? 0 : size - L.body_offset;
  const std::uint64_t data_bytes = L.points * L.point_step;
  if (L.data == PcdLayout::Data::binary) {
    if (body < data_bytes)
      throw InputError(path, "binary data has " + std::to_string(body) + " bytes, the header's " +
                                 std::to_string(L.points) + " points need " +
                                 std::to_string(data_bytes) + " (truncated)");
    return;
  }
  // binary_compressed
  std::ifstream in(path, std::ios::binary);
  in.seekg(std::streamoff(L.body_offset));
  std::uint32_t sizes[2] = {0, 0};  // compressed, uncompressed
  if (body < 8 || !in.read(reinterpret_cast<char*>(sizes), sizeof sizes))
    throw InputError(path, "binary_compressed data lacks its two size words (truncated)");
  if (sizes[0] > body - 8)
    throw InputError(path, "binary_compressed data claims " + std::to_string(sizes[0]) +
                               " compressed bytes, the file holds " + std::to_string(body - 8) + " (truncated)");
  if (sizes[1] != data_bytes)
    throw InputError(path, "binary_compressed data claims " + std::to_string(sizes[1]) +
                               " bytes uncompressed, the header's " + std::to_string(L.points) + " points need " +
                               std::to_string(data_bytes));
  // LZF expands at most 88-fold (3 bytes for a 264-byte match).
  if (data_bytes > 88 * std::uint64_t(sizes[0]) + 32)
    throw InputError(path, "binary_compressed data: " + std::to_string(sizes[0]) + " compressed bytes cannot hold " +
                               std::to_string(data_bytes));
}

// The cloud as PCL reads it, after the checks above, with the sensor pose.
struct CheckedPcd {
  pcl::PCLPointCloud2 cloud;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
};

// One value of an ASCII body, as strtod reads a whole token (an optional
// '+'), stored as the field's type: floats rounded once from the text (a
// float out of float's range through double, as PCL's stream did), integers
// truncated and clamped to their type.
bool store_value(std::string_view token, char type, int size, std::uint8_t* out) {
  const char* s = token.data();
  const char* const end = s + token.size();
  if (s < end && *s == '+') ++s;
  if (type == 'F' && size == 4) {
    float f = 0;
    const std::from_chars_result r = std::from_chars(s, end, f);
    if (r.ec == std::errc() && r.ptr == end && r.ptr != s) return std::memcpy(out, &f, 4), true;
    if (r.ec != std::errc::result_out_of_range) return false;
  }
  double v = 0;
  const std::from_chars_result r = std::from_chars(s, end, v);
  if (r.ec != std::errc() || r.ptr != end || r.ptr == s) return false;
  if (type == 'F') {
    if (size == 4) {
      const float f = float(v);
      std::memcpy(out, &f, 4);
    } else {
      std::memcpy(out, &v, 8);
    }
    return true;
  }
  auto put = [&](auto sample) {
    using T = decltype(sample);
    const double low = double(std::numeric_limits<T>::lowest()), high = double(std::numeric_limits<T>::max());
    const double t = std::isnan(v) ? 0.0 : std::trunc(v);
    const T value = t <= low ? std::numeric_limits<T>::lowest() : t >= high ? std::numeric_limits<T>::max() : T(t);
    std::memcpy(out, &value, sizeof value);
    return true;
  };
  if (type == 'U') {
    if (size == 1) return put(std::uint8_t());
    if (size == 2) return put(std::uint16_t());
    if (size == 4) return put(std::uint32_t());
    return put(std::uint64_t());
  }
  if (size == 1) return put(std::int8_t());
  if (size == 2) return put(std::int16_t());
  if (size == 4) return put(std::int32_t());
  return put(std::int64_t());
}

// An ASCII PCD, parsed here on all cores (acquisition/text_records.h) into
// the layout PCL's reader gives: each point's fields one after another.
// Every non-empty line after DATA is a point, and must hold the header's
// number of values: PCL turned a line of another count into a point of
// zeros, and parsed each value through a stream (33 MB/s on the bunny).
CheckedPcd decode_ascii_pcd(const std::string& path, const PcdLayout& L) {
  const std::string text = read_file_from(path, L.body_offset);
  auto non_empty = [](std::string_view line) { return !line.empty(); };
  // The points are sized by the lines the file holds, not by the header's count.
  const std::vector<TextBlock> blocks = cut_records(text, 1, std::size_t(L.points), non_empty);
  const std::size_t found = record_count(blocks);
  CheckedPcd pcd;
  pcl::PCLPointCloud2& cloud = pcd.cloud;
  cloud.width = std::uint32_t(L.width);
  cloud.height = std::uint32_t(L.height);
  cloud.point_step = std::uint32_t(L.point_step);
  cloud.row_step = std::uint32_t(L.point_step * L.width);
  std::uint32_t offset = 0;
  for (std::size_t f = 0; f < L.names.size(); ++f) {
    pcl::PCLPointField field;
    field.name = L.names[f];
    field.offset = offset;
    field.datatype = std::uint8_t(pcl::getFieldType(L.sizes[f], L.types[f]));
    field.count = std::uint32_t(L.counts[f]);
    cloud.fields.push_back(field);
    offset += std::uint32_t(L.sizes[f] * L.counts[f]);
  }
  cloud.data.resize(found * std::size_t(L.point_step));
  parse_records(blocks, non_empty, [&](std::string_view line, std::size_t number, std::size_t p) {
    std::uint8_t* point = &cloud.data[p * L.point_step];
    auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
    std::size_t at = 0, values = 0;
    bool ok = true;
    for (std::size_t f = 0; ok && f < L.names.size(); ++f)
      for (int k = 0; ok && k < L.counts[f]; ++k) {
        while (at < line.size() && blank(line[at])) ++at;
        std::size_t stop = at;
        while (stop < line.size() && !blank(line[stop])) ++stop;
        ok = stop > at && store_value(line.substr(at, stop - at), L.types[f], L.sizes[f],
                                      point + cloud.fields[f].offset + std::size_t(k * L.sizes[f]));
        at = stop;
        values += ok;
      }
    while (at < line.size() && blank(line[at])) ++at;
    if (at < line.size()) ok = false;  // more values than the fields take
    if (!ok || values != L.values_per_point)
      throw InputError(path, "data line " + std::to_string(number) + ": point " + std::to_string(p) + " needs " +
                                 std::to_string(L.values_per_point) + " numbers, got '" + shown(std::string(line)) +
                                 "'");
  });
  if (found < L.points)
    throw InputError(path, "file ends at point " + std::to_string(found) + " of " + std::to_string(L.points) +
                               " (truncated)");
  const double* v = L.viewpoint;
  pcd.origin = Eigen::Vector4f(float(v[0]), float(v[1]), float(v[2]), 0.f);
  pcd.orientation = Eigen::Quaternionf(float(v[3]), float(v[4]), float(v[5]), float(v[6]));
  return pcd;
}

CheckedPcd read_checked_pcd(const std::string& path) {
  std::error_code ec;  // the throwing overload fails on e.g. an over-long name
  if (!std::filesystem::exists(path, ec)) throw InputError(path, "file does not exist");
  const PcdLayout layout = read_pcd_layout(path);
  if (layout.data == PcdLayout::Data::ascii) return decode_ascii_pcd(path, layout);
  check_pcd_body(path, layout);
  CheckedPcd pcd;
  int pcd_version = 0;
  pcl::PCDReader reader;
  if (reader.read(path, pcd.cloud, pcd.origin, pcd.orientation, pcd_version, 0) < 0)
    throw InputError(path, "PCL could not parse the PCD file (bad header or truncated data)");
  const pcl::PCLPointCloud2& cloud = pcd.cloud;
  if (cloud.width != layout.width || cloud.height != layout.height ||
      cloud.point_step != layout.point_step ||
      cloud.data.size() != std::size_t(layout.points * layout.point_step))
    throw InputError(path, "PCL read a cloud of another size than the header gives");
  if (cloud.width == 0 || cloud.height == 0) throw InputError(path, "the cloud is empty");
  return pcd;
}

// The 4-byte field `name` (float, or any 4-byte type for colours), or null.
const pcl::PCLPointField* field_of(const std::string& path, const pcl::PCLPointCloud2& cloud,
                                   std::initializer_list<const char*> names, bool any_type = false) {
  for (const auto& f : cloud.fields)
    for (const char* name : names) {
      if (f.name != name) continue;
      if (any_type ? pcl::getFieldSize(f.datatype) != 4 : f.datatype != pcl::PCLPointField::FLOAT32)
        continue;
      if (std::uint64_t(f.offset) + 4 > cloud.point_step)
        throw InputError(path, "field '" + f.name + "' lies outside the point");
      return &f;
    }
  return nullptr;
}

float float_at(const std::uint8_t* point, const pcl::PCLPointField* f) {
  float v;
  std::memcpy(&v, point + f->offset, 4);
  return v;
}

Rgb color_at(const std::uint8_t* point, const pcl::PCLPointField* f) {
  std::uint32_t packed;
  std::memcpy(&packed, point + f->offset, 4);
  return Rgb{std::uint8_t(packed >> 16), std::uint8_t(packed >> 8), std::uint8_t(packed)};
}

}  // namespace

bool pcd_is_organized(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path, "file does not exist");
  return read_pcd_layout(path).height > 1;
}

PointCloud read_unorganized_pcd(const std::string& path) {
  CheckedPcd pcd = read_checked_pcd(path);
  const pcl::PCLPointCloud2& cloud = pcd.cloud;
  const pcl::PCLPointField* fx = field_of(path, cloud, {"x"});
  const pcl::PCLPointField* fy = field_of(path, cloud, {"y"});
  const pcl::PCLPointField* fz = field_of(path, cloud, {"z"});
  if (!fx || !fy || !fz) throw InputError(path, "the cloud needs float fields x, y and z");
  const pcl::PCLPointField* fn[3] = {field_of(path, cloud, {"normal_x", "nx"}),
                                     field_of(path, cloud, {"normal_y", "ny"}),
                                     field_of(path, cloud, {"normal_z", "nz"})};
  const bool normals = fn[0] && fn[1] && fn[2];
  const pcl::PCLPointField* frgb = field_of(path, cloud, {"rgb", "rgba"}, true);
  const Eigen::Matrix3f rotation = pcd.orientation.normalized().toRotationMatrix();
  const Vec3f origin = pcd.origin.head<3>();
  PointCloud out;
  out.source = path;
  const std::size_t n = std::size_t(cloud.width) * cloud.height;
  out.positions.reserve(n);
  if (normals) out.normals.reserve(n);
  if (frgb) out.colors.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* src = &cloud.data[i * cloud.point_step];
    const Vec3f p(float_at(src, fx), float_at(src, fy), float_at(src, fz));
    if (!p.allFinite()) continue;  // no return
    out.positions.push_back(rotation * p + origin);
    if (normals) out.normals.push_back(rotation * Vec3f(float_at(src, fn[0]), float_at(src, fn[1]), float_at(src, fn[2])));
    if (frgb) out.colors.push_back(color_at(src, frgb));
  }
  if (out.positions.empty()) throw InputError(path, "the cloud has no finite points");
  // PCL writes VIEWPOINT 0 0 0 1 0 0 0 when it knows no sensor: only another one names a sensor.
  if (origin.squaredNorm() > 0.f || !rotation.isIdentity(1e-6f)) out.viewpoint = origin;
  return out;
}

RangeImage read_organized_pcd(const std::string& path, ScanPose* pose) {
  CheckedPcd pcd = read_checked_pcd(path);
  const pcl::PCLPointCloud2& cloud = pcd.cloud;
  const Eigen::Vector4f& origin = pcd.origin;
  const Eigen::Quaternionf& orientation = pcd.orientation;
  if (cloud.height == 1)
    throw InputError(path, "the cloud is not organized (height 1); a range image needs "
                           "width x height with NaN for no return");
  const pcl::PCLPointField* fx = field_of(path, cloud, {"x"});
  const pcl::PCLPointField* fy = field_of(path, cloud, {"y"});
  const pcl::PCLPointField* fz = field_of(path, cloud, {"z"});
  if (!fx || !fy || !fz) throw InputError(path, "the cloud needs float fields x, y and z");
  const pcl::PCLPointField* frgb = field_of(path, cloud, {"rgb", "rgba"}, true);

  RangeImage image;
  image.cols = int(cloud.width);
  image.rows = int(cloud.height);
  image.source = path;
  image.viewpoint = Vec3f::Zero();
  const std::size_t n = std::size_t(cloud.width) * cloud.height;
  image.points.resize(n);
  if (frgb) image.colors.resize(n);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::size_t valid = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* src = &cloud.data[i * cloud.point_step];
    Vec3f p;
    std::memcpy(&p.x(), src + fx->offset, 4);
    std::memcpy(&p.y(), src + fy->offset, 4);
    std::memcpy(&p.z(), src + fz->offset, 4);
    if (p.allFinite()) ++valid;
    else p = Vec3f(nan, nan, nan);
    image.points[i] = p;
    if (frgb) image.colors[i] = color_at(src, frgb);
  }
  if (valid == 0) throw InputError(path, "the cloud has no finite points");
  if (pose) {
    pose->rotation = orientation.normalized().toRotationMatrix();
    pose->translation = origin.head<3>();
  }
  return image;
}

}  // namespace scan2lod
