#include <scan2lod/acquisition/las_file.h>

#include <scan2lod/core/error.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

namespace scan2lod {
namespace {

// Byte offsets of the public header block's fields (LAS 1.4 R15, Table 3).
enum HeaderField : std::size_t {
  kVersionMajor = 24,
  kVersionMinor = 25,
  kHeaderSize = 94,
  kPointDataOffset = 96,
  kVlrCount = 100,
  kPointFormat = 104,
  kRecordLength = 105,
  kLegacyPointCount = 107,
  kScale = 131,   // x, y, z doubles
  kOffset = 155,  // x, y, z doubles
  kMaxX = 179,    // max x, min x, max y, min y, max z, min z
  kEvlrStart = 235,
  kEvlrCount = 243,
  kPointCount = 247,
};

// The header block's size in each version: 1.3 added the waveform data
// start, 1.4 the EVLRs and the 64-bit counts.
std::size_t header_size_of(int minor) { return minor <= 2 ? 227 : minor == 3 ? 235 : 375; }

// Bytes of each point data record format's own fields (LAS 1.4 R15, Tables
// 7 to 17); a record may be longer (extra bytes).
constexpr std::size_t kFormatLength[11] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
// Where a format's red, green, blue (three uint16) start; -1: no colour.
constexpr int kRgbAt[11] = {-1, -1, 20, 28, -1, 28, -1, 30, 30, -1, 30};

constexpr std::size_t kVlrHeader = 54;   // reserved, user id, record id, length (u16), description
constexpr std::size_t kEvlrHeader = 60;  // the same with a 64-bit length

// Little-endian fields, whatever the host's order.
std::uint64_t le(const unsigned char* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
std::int32_t le_i32(const unsigned char* p) { return std::int32_t(std::uint32_t(le(p, 4))); }
double le_f64(const unsigned char* p) {
  const std::uint64_t bits = le(p, 8);
  double v;
  std::memcpy(&v, &bits, 8);
  return v;
}

std::string number(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

std::uint64_t file_size(const std::string& path) {
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path, "cannot tell the file's size: " + ec.message());
  return size;
}

// Reads `count` bytes at `at`; throws naming what they were to hold.
std::vector<unsigned char> bytes_at(const std::string& path, std::ifstream& in, std::uint64_t at, std::size_t count,
                                    const std::string& what) {
  std::vector<unsigned char> bytes(count);
  in.clear();
  in.seekg(std::streamoff(at));
  if (!in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(count)))
    throw InputError(path, "file ends inside " + what + " (at byte " + std::to_string(at) + ", truncated)");
  return bytes;
}

// Phase: the signature, the version and the header block's own size.
int check_version(const std::string& path, const std::vector<unsigned char>& h, std::uint64_t size) {
  if (size < 4 || std::memcmp(h.data(), "LASF", 4) != 0)
    throw InputError(path, "not a LAS file: it does not start with the signature 'LASF'");
  if (size < 227)
    throw InputError(path, "public header block: the file has " + std::to_string(size) +
                               " bytes, a LAS header needs at least 227 (truncated)");
  const int major = h[kVersionMajor], minor = h[kVersionMinor];
  if (major != 1 || minor > 4)
    throw InputError(path, "public header block: version " + std::to_string(major) + "." + std::to_string(minor) +
                               "; expected LAS 1.0 to 1.4");
  const std::size_t header_size = std::size_t(le(&h[kHeaderSize], 2));
  if (header_size < header_size_of(minor))
    throw InputError(path, "public header block: header size " + std::to_string(header_size) + " bytes; LAS 1." +
                               std::to_string(minor) + " needs at least " + std::to_string(header_size_of(minor)));
  if (header_size > size)
    throw InputError(path, "public header block: header size " + std::to_string(header_size) + " bytes, the file has " +
                               std::to_string(size) + " (truncated)");
  return minor;
}

// Phase: point format and record length; LAZ is told apart here too, as
// LASzip marks its point formats with bit 7 (older writers bit 6).
void check_point_format(const std::string& path, const std::vector<unsigned char>& h, LasHeader* L) {
  const int format = h[kPointFormat];
  if (format & 0xC0) throw InputError(path, laz_refusal(path));
  if (format > 10)
    throw InputError(path, "public header block: point data record format " + std::to_string(format) +
                               "; expected 0 to 10");
  L->point_format = format;
  L->record_length = std::size_t(le(&h[kRecordLength], 2));
  if (L->record_length < kFormatLength[format])
    throw InputError(path, "public header block: point data record length " + std::to_string(L->record_length) +
                               " bytes; format " + std::to_string(format) + " needs at least " +
                               std::to_string(kFormatLength[format]));
}

// Phase: scale, offset and bounds.
void read_frame(const std::string& path, const std::vector<unsigned char>& h, LasHeader* L) {
  static const char* const kAxis[3] = {"X", "Y", "Z"};
  for (int a = 0; a < 3; ++a) {
    L->scale[a] = le_f64(&h[kScale + 8 * std::size_t(a)]);
    L->offset[a] = le_f64(&h[kOffset + 8 * std::size_t(a)]);
    L->max[a] = le_f64(&h[kMaxX + 16 * std::size_t(a)]);
    L->min[a] = le_f64(&h[kMaxX + 16 * std::size_t(a) + 8]);
    if (!std::isfinite(L->scale[a]) || L->scale[a] == 0.0)
      throw InputError(path, std::string("public header block: ") + kAxis[a] + " scale factor " +
                                 number(L->scale[a]) + "; expected a finite, non-zero number (e.g. 0.01)");
    if (!std::isfinite(L->offset[a]))
      throw InputError(path, std::string("public header block: ") + kAxis[a] + " offset " + number(L->offset[a]) +
                                 "; expected a finite number");
  }
}

// Phase: the VLRs between the header block and the points must end where the
// points begin, or before.
void check_vlrs(const std::string& path, std::ifstream& in, const std::vector<unsigned char>& h, const LasHeader& L,
                std::size_t header_size, std::uint64_t size) {
  const std::uint64_t count = le(&h[kVlrCount], 4);
  if (L.point_data_offset < header_size)
    throw InputError(path, "public header block: offset to point data " + std::to_string(L.point_data_offset) +
                               " lies inside the " + std::to_string(header_size) + "-byte header");
  if (L.point_data_offset > size)
    throw InputError(path, "public header block: offset to point data " + std::to_string(L.point_data_offset) +
                               " lies past the file's end (" + std::to_string(size) + " bytes; truncated)");
  if (count > (L.point_data_offset - header_size) / kVlrHeader)
    throw InputError(path, "public header block: " + std::to_string(count) + " VLRs cannot fit in the " +
                               std::to_string(L.point_data_offset - header_size) +
                               " bytes between the header and the points");
  std::uint64_t at = header_size;
  for (std::uint64_t k = 0; k < count; ++k) {
    if (at + kVlrHeader > L.point_data_offset)
      throw InputError(path, "VLR " + std::to_string(k) + " of " + std::to_string(count) + " starts at byte " +
                                 std::to_string(at) + ", too close to the points (byte " +
                                 std::to_string(L.point_data_offset) + ") for its 54-byte header");
    const std::vector<unsigned char> v = bytes_at(path, in, at, kVlrHeader, "VLR " + std::to_string(k));
    at += kVlrHeader + le(&v[20], 2);
    if (at > L.point_data_offset)
      throw InputError(path, "VLR " + std::to_string(k) + " of " + std::to_string(count) + " ends at byte " +
                                 std::to_string(at) + ", past the start of the point data (byte " +
                                 std::to_string(L.point_data_offset) + ")");
  }
}

// Phase: the point count, which must fit between the point data's start and
// the EVLRs (1.4) or the file's end.
void check_points_and_evlrs(const std::string& path, std::ifstream& in, const std::vector<unsigned char>& h,
                            LasHeader* L, std::uint64_t size) {
  const std::uint64_t legacy = le(&h[kLegacyPointCount], 4);
  L->points = legacy;
  std::uint64_t end = size;  // of the point data
  std::uint64_t evlrs = 0, evlr_start = 0;
  if (L->version_minor >= 4) {
    const std::uint64_t wide = le(&h[kPointCount], 8);
    if (wide != 0 && legacy != 0 && wide != legacy)
      throw InputError(path, "public header block: legacy point count " + std::to_string(legacy) +
                                 " differs from the 64-bit count " + std::to_string(wide) + "; expected the same");
    if (wide != 0) L->points = wide;
    evlrs = le(&h[kEvlrCount], 4);
    evlr_start = le(&h[kEvlrStart], 8);
    if (evlrs > 0) {
      if (evlr_start < L->point_data_offset || evlr_start > size)
        throw InputError(path, "public header block: start of the first EVLR, byte " + std::to_string(evlr_start) +
                                   ", lies outside [" + std::to_string(L->point_data_offset) + ", " +
                                   std::to_string(size) + "] (after the points, within the file)");
      end = evlr_start;
    }
  }
  const std::uint64_t room = end - L->point_data_offset;
  if (L->points > room / L->record_length)
    throw InputError(path, "public header block: " + std::to_string(L->points) + " points of " +
                               std::to_string(L->record_length) + " bytes need " +
                               (L->points > ~std::uint64_t(0) / L->record_length
                                    ? std::string("more bytes than any file holds")
                                    : std::to_string(L->points * L->record_length) + " bytes") +
                               " from byte " + std::to_string(L->point_data_offset) + ", the file has " +
                               std::to_string(room) + (evlrs ? " before its EVLRs" : "") + " (truncated)");
  if (evlrs > (size - evlr_start) / kEvlrHeader)
    throw InputError(path, "public header block: " + std::to_string(evlrs) + " EVLRs cannot fit in the " +
                               std::to_string(size - evlr_start) + " bytes from byte " + std::to_string(evlr_start));
  std::uint64_t at = evlr_start;
  for (std::uint64_t k = 0; k < evlrs; ++k) {
    if (size - at < kEvlrHeader)
      throw InputError(path, "EVLR " + std::to_string(k) + " of " + std::to_string(evlrs) + " starts at byte " +
                                 std::to_string(at) + ", too close to the file's end for its 60-byte header (truncated)");
    const std::vector<unsigned char> v = bytes_at(path, in, at, kEvlrHeader, "EVLR " + std::to_string(k));
    const std::uint64_t length = le(&v[20], 8);
    if (length > size - at - kEvlrHeader)
      throw InputError(path, "EVLR " + std::to_string(k) + " of " + std::to_string(evlrs) + " at byte " +
                                 std::to_string(at) + " holds " + std::to_string(length) +
                                 " bytes, past the file's end (" + std::to_string(size) + " bytes; truncated)");
    at += kEvlrHeader + length;
  }
}

Vec3d record_coordinates(const unsigned char* r, const LasHeader& L) {
  return Vec3d(double(le_i32(r)) * L.scale.x() + L.offset.x(), double(le_i32(r + 4)) * L.scale.y() + L.offset.y(),
               double(le_i32(r + 8)) * L.scale.z() + L.offset.z());
}

// Phase: the point records, decoded block by block.
void read_records(const std::string& path, const LasHeader& L, const Vec3d& origin, PointCloud* cloud,
                  Vec3d* low, Vec3d* high) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file");
  in.seekg(std::streamoff(L.point_data_offset));
  const std::size_t n = std::size_t(L.points);
  cloud->positions.resize(n);
  const int rgb_at = kRgbAt[L.point_format];
  std::vector<std::array<std::uint16_t, 3>> wide_colors(rgb_at >= 0 ? n : 0);
  const std::size_t block_records = std::min(n, std::max<std::size_t>(1, (std::size_t(1) << 22) / L.record_length));
  std::vector<unsigned char> block(block_records * L.record_length);
  *low = Vec3d::Constant(std::numeric_limits<double>::infinity());
  *high = -*low;
  for (std::size_t first = 0; first < n; first += block_records) {
    const std::size_t count = std::min(block_records, n - first);
    if (!in.read(reinterpret_cast<char*>(block.data()), std::streamsize(count * L.record_length)))
      throw InputError(path, "file ends at point record " + std::to_string(first + std::size_t(in.gcount()) / L.record_length) +
                                 " of " + std::to_string(n) + " (truncated while reading)");
    for (std::size_t i = 0; i < count; ++i) {
      const unsigned char* r = &block[i * L.record_length];
      const Vec3d p = record_coordinates(r, L);
      *low = low->cwiseMin(p);
      *high = high->cwiseMax(p);
      const Vec3f local = (p - origin).cast<float>();
      // A scale of 1e30 is well-formed too; such points would vanish as NaN later.
      if (!local.allFinite())
        throw InputError(path, "point record " + std::to_string(first + i) + " lies at (" + number(p.x()) + ", " +
                                   number(p.y()) + ", " + number(p.z()) + "), beyond a float's range from the origin (" +
                                   number(origin.x()) + ", " + number(origin.y()) + ", " + number(origin.z()) +
                                   "): expected coordinates of a survey (check the scale and offset)");
      cloud->positions[first + i] = local;
      if (rgb_at >= 0)
        for (int c = 0; c < 3; ++c)
          wide_colors[first + i][std::size_t(c)] = std::uint16_t(le(r + rgb_at + 2 * c, 2));
    }
  }
  if (rgb_at < 0) return;
  std::uint16_t brightest = 0;
  for (const auto& c : wide_colors) brightest = std::max({brightest, c[0], c[1], c[2]});
  const int shift = brightest > 255 ? 8 : 0;
  cloud->colors.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) cloud->colors[i][std::size_t(c)] = std::uint8_t(wide_colors[i][std::size_t(c)] >> shift);
}

// Whether the header's bounds hold [low, high], give or take a scale step.
bool bounds_hold(const LasHeader& L, const Vec3d& low, const Vec3d& high) {
  for (int a = 0; a < 3; ++a) {
    const double slack = std::fabs(L.scale[a]);
    if (!(low[a] >= L.min[a] - slack && high[a] <= L.max[a] + slack)) return false;
  }
  return true;
}

std::string box(const Vec3d& low, const Vec3d& high) {
  return "x " + number(low.x()) + " to " + number(high.x()) + ", y " + number(low.y()) + " to " + number(high.y()) +
         ", z " + number(low.z()) + " to " + number(high.z());
}

}  // namespace

std::string laz_refusal(const std::string& path) {
  const std::string stem = std::filesystem::path(path).stem().string();
  return "is LAZ (LASzip-compressed LAS); reading it needs LASzip, which Debian does not package. "
         "Convert it to LAS first, e.g. 'laszip -i " + stem + ".laz -o " + stem + ".las' or 'pdal translate " +
         stem + ".laz " + stem + ".las', and give the .las";
}

LasHeader read_las_header(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file");
  const std::uint64_t size = file_size(path);
  std::vector<unsigned char> h(375, 0);
  in.read(reinterpret_cast<char*>(h.data()), std::streamsize(h.size()));
  LasHeader L;
  L.version_minor = check_version(path, h, size);
  const std::size_t header_size = std::size_t(le(&h[kHeaderSize], 2));
  check_point_format(path, h, &L);
  read_frame(path, h, &L);
  L.point_data_offset = le(&h[kPointDataOffset], 4);
  check_vlrs(path, in, h, L, header_size, size);
  check_points_and_evlrs(path, in, h, &L, size);
  if (L.points > 0)
    L.first_point = record_coordinates(bytes_at(path, in, L.point_data_offset, 12, "point record 0").data(), L);
  return L;
}

Vec3d las_local_origin(const LasHeader& L) {
  Vec3d centre = 0.5 * (L.min + L.max);
  const bool usable = centre.allFinite() && (!L.first_point || bounds_hold(L, *L.first_point, *L.first_point));
  if (!usable) centre = L.first_point ? *L.first_point : L.offset;
  Vec3d origin;
  for (int a = 0; a < 3; ++a) {
    origin[a] = L.offset[a] + std::round((centre[a] - L.offset[a]) / L.scale[a]) * L.scale[a];
    if (!std::isfinite(origin[a])) origin[a] = L.offset[a];
  }
  return origin;
}

PointCloud read_las(const std::string& path, const Vec3d& origin) {
  const LasHeader L = read_las_header(path);
  PointCloud cloud;
  cloud.source = path;
  cloud.origin = origin;
  cloud.sensor_direction = Vec3f::UnitZ();
  Vec3d low, high;
  read_records(path, L, origin, &cloud, &low, &high);
  if (L.points > 0 && !bounds_hold(L, low, high))
    cloud.warnings.push_back(path + ": the header's bounds (" + box(L.min, L.max) + ") do not hold the points (" +
                             box(low, high) + "); read all the same");
  return cloud;
}

PointCloud read_las(const std::string& path) { return read_las(path, las_local_origin(read_las_header(path))); }

}  // namespace scan2lod
