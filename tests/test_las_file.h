// LAS files for the tests, written from the ASPRS "LAS Specification 1.4 -
// R15": a header block, VLRs, point records of any format 0 to 10 (with
// extra bytes) and EVLRs, with junk in the fields the reader does not use.
#pragma once

#include <scan2lod/core/types.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace scan2lod::testing {

using Rgb16 = std::array<std::uint16_t, 3>;

// What a test file holds. Coordinates are the integers X, Y, Z of the
// records; the file frame's point is X * scale + offset.
struct LasFile {
  int minor = 4;
  int format = 0;
  std::size_t extra_bytes = 0;  // after the format's own fields
  int vlrs = 1;
  int evlrs = 0;  // 1.4 only
  Vec3d scale = Vec3d::Constant(0.001);
  Vec3d offset = Vec3d(500000, 5000000, 300);
  std::vector<std::array<std::int32_t, 3>> records;
  std::vector<Rgb16> colors;  // one per record where the format has colour
  long long header_count = -1;  // the count the header states; -1: records.size()
};

constexpr std::size_t kFormatLength[11] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
constexpr int kRgbAt[11] = {-1, -1, 20, 28, -1, 28, -1, 30, 30, -1, 30};

template <class T>
inline void put(std::string* bytes, std::size_t at, T value) {
  std::memcpy(&(*bytes)[at], &value, sizeof value);  // the machines are little-endian, as LAS is
}

// The file's bytes: header block, VLRs, point records, EVLRs. Fields the
// reader does not use are filled with junk, so that reading them would show.
inline std::string las_bytes(const LasFile& f) {
  const std::size_t header_size = f.minor <= 2 ? 227 : f.minor == 3 ? 235 : 375;
  const std::size_t record_length = kFormatLength[f.format] + f.extra_bytes;
  std::string vlrs;
  for (int k = 0; k < f.vlrs; ++k) {
    std::string v(54 + 10 + k, char(0x5a));
    put<std::uint16_t>(&v, 20, std::uint16_t(10 + k));
    vlrs += v;
  }
  const std::uint64_t count = f.header_count >= 0 ? std::uint64_t(f.header_count) : f.records.size();
  std::string h(header_size, '\0');
  std::memcpy(&h[0], "LASF", 4);
  h[24] = 1;
  h[25] = char(f.minor);
  std::memcpy(&h[26], "scan2lod test", 13);
  put<std::uint16_t>(&h, 94, std::uint16_t(header_size));
  put<std::uint32_t>(&h, 96, std::uint32_t(header_size + vlrs.size()));
  put<std::uint32_t>(&h, 100, std::uint32_t(f.vlrs));
  h[104] = char(f.format);
  put<std::uint16_t>(&h, 105, std::uint16_t(record_length));
  // LAS 1.4 keeps the legacy count zero for formats 6 to 10.
  put<std::uint32_t>(&h, 107, f.minor >= 4 && f.format >= 6 ? 0u : std::uint32_t(count));
  Vec3d low = Vec3d::Constant(1e300), high = -low;
  for (const auto& r : f.records)
    for (int a = 0; a < 3; ++a) {
      const double p = r[std::size_t(a)] * f.scale[a] + f.offset[a];
      low[a] = std::min(low[a], p), high[a] = std::max(high[a], p);
    }
  for (int a = 0; a < 3; ++a) {
    put<double>(&h, 131 + 8 * std::size_t(a), f.scale[a]);
    put<double>(&h, 155 + 8 * std::size_t(a), f.offset[a]);
    put<double>(&h, 179 + 16 * std::size_t(a), high[a]);
    put<double>(&h, 187 + 16 * std::size_t(a), low[a]);
  }
  std::string points;
  for (std::size_t i = 0; i < f.records.size(); ++i) {
    std::string r(record_length, char(0xa5));
    for (int a = 0; a < 3; ++a) put<std::int32_t>(&r, 4 * std::size_t(a), f.records[i][std::size_t(a)]);
    if (kRgbAt[f.format] >= 0)
      for (int c = 0; c < 3; ++c) put<std::uint16_t>(&r, std::size_t(kRgbAt[f.format] + 2 * c), f.colors[i][std::size_t(c)]);
    points += r;
  }
  std::string evlrs;
  for (int k = 0; k < f.evlrs; ++k) {
    std::string v(60 + 100 * std::size_t(k + 1), char(0x3c));
    put<std::uint64_t>(&v, 20, 100 * std::uint64_t(k + 1));
    evlrs += v;
  }
  if (f.minor >= 4) {
    put<std::uint64_t>(&h, 235, f.evlrs ? header_size + vlrs.size() + points.size() : 0);
    put<std::uint32_t>(&h, 243, std::uint32_t(f.evlrs));
    put<std::uint64_t>(&h, 247, count);
  }
  return h + vlrs + points + evlrs;
}

// n records scattered over a box of `size` metres above the offset.
inline LasFile scattered(int minor, int format, std::size_t n, double size, std::uint32_t seed) {
  LasFile f;
  f.minor = minor;
  f.format = format;
  std::mt19937 random(seed);
  std::uniform_int_distribution<std::int32_t> coordinate(0, std::int32_t(size / 0.001));
  std::uniform_int_distribution<int> channel(0, 65535);
  for (std::size_t i = 0; i < n; ++i) {
    f.records.push_back({coordinate(random), coordinate(random), coordinate(random) / 10});
    f.colors.push_back({std::uint16_t(channel(random)), std::uint16_t(channel(random)), std::uint16_t(channel(random))});
  }
  return f;
}

}  // namespace scan2lod::testing
