// LAS input (acquisition/las_file.h), checked on files written here from the
// ASPRS "LAS Specification 1.4 - R15": every version 1.1 to 1.4 and every
// point format 0 to 10 reads the header's points, with extra bytes, VLRs and
// EVLRs skipped; georeferenced coordinates come back within the file's scale
// once the local origin is added back; a terrain written as LAS reconstructs
// onto its points; LAZ and broken files are refused naming what was expected.
#include <scan2lod/acquisition/las_file.h>
#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/core/error.h>
#include <scan2lod/measure/surface_distance.h>
#include <scan2lod/reconstruct/marching_cubes.h>

#include "test_las_file.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

using namespace scan2lod;
using namespace scan2lod::testing;
namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) { return scan2lod::testing::scratch_folder("las") / name; }

void spit(const fs::path& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

// The largest distance, in the file's frame, between a record's exact
// coordinates and its point read back with the origin added.
double worst_error(const LasFile& f, const PointCloud& cloud) {
  double worst = 0;
  for (std::size_t i = 0; i < f.records.size() && i < cloud.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      const double exact = f.records[i][std::size_t(a)] * f.scale[a] + f.offset[a];
      worst = std::max(worst, std::fabs(cloud.origin[a] + double(cloud.positions[i][a]) - exact));
    }
  return worst;
}

std::string error_of(const std::string& path) {
  try {
    read_las(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(LasFile, EveryVersionAndPointFormatReadsTheHeadersPoints) {
  int files = 0;
  for (int minor = 1; minor <= 4; ++minor)
    for (int format = 0; format <= 10; ++format) {
      SCOPED_TRACE("LAS 1." + std::to_string(minor) + " format " + std::to_string(format));
      LasFile f = scattered(minor, format, 200, 800.0, std::uint32_t(17 * minor + format));
      f.extra_bytes = std::size_t(format % 3) * 5;  // 0, 5 or 10 extra bytes
      f.vlrs = format % 3;
      f.evlrs = minor == 4 ? 1 + format % 2 : 0;
      const fs::path path = scratch("v1" + std::to_string(minor) + "_f" + std::to_string(format) + ".las");
      spit(path, las_bytes(f));
      const PointCloud cloud = read_las(path.string());
      ASSERT_EQ(cloud.size(), f.records.size());
      EXPECT_LE(worst_error(f, cloud), 0.0005);  // within half the 1 mm scale
      EXPECT_TRUE(cloud.normals.empty());
      ASSERT_TRUE(cloud.sensor_direction.has_value());
      EXPECT_EQ(*cloud.sensor_direction, Vec3f::UnitZ());
      EXPECT_TRUE(cloud.warnings.empty()) << cloud.warnings.front();
      if (kRgbAt[format] < 0) {
        EXPECT_TRUE(cloud.colors.empty());
      } else {
        ASSERT_EQ(cloud.colors.size(), cloud.size());
        for (std::size_t i = 0; i < cloud.size(); ++i)
          for (std::size_t c = 0; c < 3; ++c) ASSERT_EQ(cloud.colors[i][c], f.colors[i][c] >> 8);
      }
      ++files;
    }
  EXPECT_EQ(files, 44);
}

TEST(LasFile, ThePointCountIsTheHeaders) {
  // 1.4 with 64-bit counts, 1.2 with the legacy one: 300 records on disk, the header names 120.
  for (const int minor : {2, 4}) {
    LasFile f = scattered(minor, minor == 4 ? 6 : 1, 300, 50.0, 5);
    f.header_count = 120;
    const fs::path path = scratch("count_1" + std::to_string(minor) + ".las");
    spit(path, las_bytes(f));
    const PointCloud cloud = read_las(path.string());
    EXPECT_EQ(cloud.size(), 120u);
    EXPECT_LE(worst_error(f, cloud), 0.0005);
  }
}

// The case: a UTM-sized offset (500 000 m east, 5 000 000 m north,
// 300 m up) at 1 mm scale. A float holds 5 000 000.123 only to 0.5 m; the
// local origin keeps every point within the scale.
TEST(LasFile, UtmCoordinatesReadBackWithinTheScale) {
  LasFile f = scattered(4, 7, 5000, 2000.0, 11);  // a 2 km tile
  const fs::path path = scratch("utm.las");
  spit(path, las_bytes(f));
  const LasHeader header = read_las_header(path.string());
  const PointCloud cloud = read_las(path.string());
  EXPECT_LE(worst_error(f, cloud), 0.0005);
  // The origin is a coordinate of the file's own grid, inside the tile.
  for (int a = 0; a < 3; ++a) {
    const double steps = (cloud.origin[a] - f.offset[a]) / f.scale[a];
    EXPECT_NEAR(steps, std::round(steps), 1e-6);
    EXPECT_GE(cloud.origin[a], header.min[a]);
    EXPECT_LE(cloud.origin[a], header.max[a]);
  }
  EXPECT_GT(cloud.origin.y(), 4.9e6);
  // A header whose bounds are left zero: the origin falls back on the first
  // point, and the reader says the bounds are wrong.
  std::string bytes = las_bytes(f);
  std::memset(&bytes[179], 0, 48);
  spit(path, bytes);
  const PointCloud zeroed = read_las(path.string());
  EXPECT_LE(worst_error(f, zeroed), 0.0005);
  ASSERT_EQ(zeroed.warnings.size(), 1u);
  EXPECT_NE(zeroed.warnings[0].find("header's bounds"), std::string::npos) << zeroed.warnings[0];
}

TEST(LasFile, EightBitColoursAreKeptAsTheyAre) {
  LasFile f = scattered(2, 2, 50, 10.0, 3);
  for (Rgb16& c : f.colors)
    for (std::uint16_t& v : c) v &= 0xff;
  const fs::path path = scratch("colours8.las");
  spit(path, las_bytes(f));
  const PointCloud cloud = read_las(path.string());
  ASSERT_EQ(cloud.colors.size(), 50u);
  for (std::size_t i = 0; i < 50; ++i)
    for (std::size_t c = 0; c < 3; ++c) EXPECT_EQ(cloud.colors[i][c], f.colors[i][c]);
}

// Every input shares one origin (the first LAS file's), so two tiles keep
// their places; the report carries it for the writers.
TEST(LasFile, TilesAndOtherInputsShareTheFirstTilesOrigin) {
  LasFile a = scattered(4, 6, 400, 100.0, 1), b = scattered(3, 1, 400, 100.0, 2);
  b.offset.x() += 100.0;  // the next tile east
  spit(scratch("tile_a.las"), las_bytes(a));
  spit(scratch("tile_b.las"), las_bytes(b));
  AcquisitionReport report;
  AcquisitionOptions options;
  const OrientedPoints points =
      load_oriented_points({scratch("tile_a.las").string(), scratch("tile_b.las").string()}, options, &report);
  EXPECT_EQ(report.origin, las_local_origin(read_las_header(scratch("tile_a.las").string())));
  EXPECT_EQ(report.clouds_estimated, 2u);
  // Every loaded point, with the origin added, is one of the two tiles' records.
  double worst = 0;
  std::size_t b_points = 0;
  for (const Vec3f& p : points.positions) {
    const Vec3d q = report.origin + p.cast<double>();
    b_points += q.x() > b.offset.x();
    double nearest = 1e9;
    for (const LasFile* f : {&a, &b})
      for (const auto& r : f->records) {
        double d = 0;
        for (int k = 0; k < 3; ++k) d = std::max(d, std::fabs(q[k] - (r[std::size_t(k)] * f->scale[k] + f->offset[k])));
        nearest = std::min(nearest, d);
      }
    worst = std::max(worst, nearest);
  }
  EXPECT_LE(worst, 0.0005);
  EXPECT_GT(b_points, 300u);
}

// An airborne survey of a hill: normals estimated and turned up (+Z, the
// sensor far above), and the mesh reconstructed from them lies on the points.
TEST(LasFile, ATerrainReconstructsOntoItsPoints) {
  auto hill = [](double x, double y) { return 12.0 * std::exp(-(x * x + y * y) / 200.0) + 0.05 * x; };
  LasFile f;
  f.format = 3;
  const int n = 120;  // 120 x 120 returns over 60 m, 0.5 m apart
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double x = 0.5 * i - 30, y = 0.5 * j - 30;
      const double z = hill(x, y);
      f.records.push_back({std::int32_t(std::lround((x + 1000) / 0.001)), std::int32_t(std::lround((y + 2000) / 0.001)),
                           std::int32_t(std::lround(z / 0.001))});
      f.colors.push_back({std::uint16_t(i * 500), std::uint16_t(j * 500), 30000});
    }
  const fs::path path = scratch("hill.las");
  spit(path, las_bytes(f));
  AcquisitionReport report;
  const OrientedPoints points = load_oriented_points({path.string()}, {}, &report);
  ASSERT_EQ(points.size(), std::size_t(n * n));
  EXPECT_EQ(report.origin, las_local_origin(read_las_header(path.string())));
  EXPECT_GT(report.origin.y(), 5.0e6);
  std::size_t up = 0;
  for (const Vec3f& normal : points.normals) up += normal.z() > 0.f;
  EXPECT_EQ(up, points.size());
  ASSERT_TRUE(points.has_colors());

  ReconstructOptions options;
  options.resolution = 128;
  const Reconstruction r = reconstruct(points, options);
  ASSERT_GT(r.mesh.triangles.size(), 10000u);
  // The returns lie on the mesh, to a small share of the 0.5 m spacing (1 mm mean).
  const DistanceStats to_mesh = distance_stats(distances_to_surface(points.positions, r.mesh));
  EXPECT_LT(to_mesh.mean, 0.005);
  EXPECT_LT(to_mesh.p95, 0.01);
  // The mesh on the hill: each vertex, back in the file's frame, against the
  // surface sampled (the 1 mm grid rounds it by 0.5 mm); past the rim of the
  // returns the surface may run on by a few cubes, never more.
  double worst_height = 0, worst_rim = 0, sum = 0;
  for (const Vec3f& v : r.mesh.positions) {
    const Vec3d q = report.origin + v.cast<double>() - Vec3d(f.offset.x() + 1000, f.offset.y() + 2000, f.offset.z());
    worst_height = std::max(worst_height, std::fabs(q.z() - hill(q.x(), q.y())));
    sum += std::fabs(q.z() - hill(q.x(), q.y()));
    worst_rim = std::max({worst_rim, -30 - q.x(), q.x() - 29.5, -30 - q.y(), q.y() - 29.5});
  }
  EXPECT_LT(sum / double(r.mesh.positions.size()), 0.005);  // 2.2 mm when written
  EXPECT_LT(worst_height, 0.05);                             // a tenth of the spacing; 25 mm
  // ReconstructOptions::reach: 2.5 spacings (0.5 m) and a 0.47 m cube; 1.49 m.
  EXPECT_LT(worst_rim, 2.0);
}

TEST(LasFile, LazIsRefusedWithHowToConvert) {
  const fs::path laz = scratch("survey.laz");
  LasFile f = scattered(2, 3, 10, 10.0, 9);
  spit(laz, las_bytes(f));
  std::string message;
  try {
    load_oriented_points({laz.string()});
  } catch (const InputError& e) {
    message = e.what();
  }
  for (const char* words : {"survey.laz", "LAZ", "LASzip", "Debian", "laszip -i survey.laz -o survey.las",
                            "pdal translate survey.laz survey.las"})
    EXPECT_NE(message.find(words), std::string::npos) << words << " in: " << message;
  // A LAZ named .las: LASzip marks the point format with bit 7.
  std::string bytes = las_bytes(f);
  bytes[104] = char(0x80 | 3);
  spit(scratch("survey_z.las"), bytes);
  EXPECT_NE(error_of(scratch("survey_z.las").string()).find("LAZ"), std::string::npos);
}

struct BadLas {
  std::string name, bytes, expect;
};

TEST(LasFile, BadFilesAreRefusedNamingTheFieldAndTheExpectation) {
  const LasFile good = scattered(4, 7, 20, 10.0, 4);
  LasFile with_evlr = good;
  with_evlr.evlrs = 1;
  const std::string g = las_bytes(good), e = las_bytes(with_evlr);
  auto changed = [](std::string bytes, std::size_t at, const std::string& with) {
    bytes.replace(at, with.size(), with);
    return bytes;
  };
  auto u32 = [](std::uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
  auto u64 = [](std::uint64_t v) { return std::string(reinterpret_cast<const char*>(&v), 8); };
  auto u16 = [](std::uint16_t v) { return std::string(reinterpret_cast<const char*>(&v), 2); };
  const std::uint32_t data_at = 375 + 54 + 10;  // header, one VLR of 10 bytes
  const std::vector<BadLas> cases = {
      {"empty.las", "", "signature 'LASF'"},
      {"not_las.las", "ply\nformat ascii 1.0\n" + std::string(300, ' '), "signature 'LASF'"},
      {"short_header.las", g.substr(0, 100), "needs at least 227 (truncated)"},
      {"version_2.las", changed(g, 24, "\x02"), "version 2.4; expected LAS 1.0 to 1.4"},
      {"version_1_5.las", changed(g, 25, "\x05"), "version 1.5; expected LAS 1.0 to 1.4"},
      {"header_too_small.las", changed(g, 94, u16(227)), "LAS 1.4 needs at least 375"},
      {"format_11.las", changed(g, 104, "\x0b"), "point data record format 11; expected 0 to 10"},
      {"record_too_short.las", changed(g, 105, u16(30)), "record length 30 bytes; format 7 needs at least 36"},
      {"zero_scale.las", changed(g, 139, u64(0)), "Y scale factor 0"},
      {"too_many_points.las", changed(g, 247, u64(1000000)), "1000000 points of 36 bytes need 36000000 bytes"},
      {"absurd_count.las", changed(g, 247, u64(~0ull)), "more bytes than any file holds"},
      {"counts_disagree.las", changed(changed(g, 104, "\x03"), 107, u32(19)), "legacy point count 19 differs"},
      {"truncated_points.las", g.substr(0, data_at + 36 * 19 + 5), "(truncated)"},
      {"offset_past_end.las", changed(g, 96, u32(1u << 30)), "past the file's end"},
      {"offset_inside_header.las", changed(g, 96, u32(100)), "inside the 375-byte header"},
      {"vlr_into_points.las", changed(g, 375 + 20, u16(5000)), "VLR 0 of 1 ends at byte"},
      {"too_many_vlrs.las", changed(g, 100, u32(1000)), "1000 VLRs cannot fit"},
      {"evlr_inside_points.las", changed(e, 235, u64(data_at + 36)), "EVLR"},
      {"evlr_past_end.las", changed(e, std::size_t(data_at) + 36 * 20 + 20, u64(1u << 20)), "past the file's end"},
      {"evlrs_cut_off.las", e.substr(0, e.size() - 30), "truncated"},
  };
  for (const BadLas& c : cases) {
    SCOPED_TRACE(c.name);
    spit(scratch(c.name), c.bytes);
    const std::string message = error_of(scratch(c.name).string());
    EXPECT_NE(message.find(scratch(c.name).string()), std::string::npos) << message;
    EXPECT_NE(message.find(c.expect), std::string::npos) << message;
  }
  // Every cut of a whole file short of its end is refused, none read in part.
  for (std::size_t size = 0; size < e.size(); ++size) {
    spit(scratch("cut.las"), e.substr(0, size));
    EXPECT_NE(error_of(scratch("cut.las").string()), "") << "cut at byte " << size;
  }
}
