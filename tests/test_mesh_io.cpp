// Mesh files: every format gives back what was written, and broken files give
// an InputError that names the problem instead of a crash or a partial mesh.
#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/core/error.h>
#include <scan2lod/io/mesh_file.h>

#include "test_support.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <sstream>
#include <string>

namespace scan2lod {
namespace {

namespace fs = std::filesystem;

// A fresh, empty folder per test.
fs::path scratch(const std::string& name) {
  const fs::path dir = scan2lod::testing::scratch_folder() / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Two triangles and a quad-split pair on a bent strip: distinct, non-round
// coordinates, unit normals, and distinct colours per vertex.
TriangleMesh small_mesh() {
  TriangleMesh m;
  m.positions = {{0.1234567f, -1.5f, 2.25f},  {1.0078125f, -1.25f, 2.5f},
                 {0.3f, 0.7071068f, 2.0f},     {1.3333334f, 0.5f, 1.75f},
                 {-0.45f, 0.2f, 3.1415927f}};
  m.triangles = {{0, 1, 2}, {1, 3, 2}, {0, 2, 4}, {2, 3, 4}};
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    m.normals.push_back(Vec3f(float(i) + 1, 0.5f, -0.25f * float(i)).normalized());
    m.colors.push_back(
        Rgb{std::uint8_t(10 + 40 * i), std::uint8_t(250 - 30 * i), std::uint8_t(7 * i)});
  }
  return m;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void spit(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary);
  out << bytes;
}

// Reading must either succeed or throw InputError; anything else fails the test.
enum class Outcome { read, input_error };
Outcome try_read(const fs::path& p, TriangleMesh* out = nullptr) {
  try {
    TriangleMesh m = read_mesh(p.string());
    if (out) *out = std::move(m);
    return Outcome::read;
  } catch (const InputError&) {
    return Outcome::input_error;
  }
}

std::string error_of(const std::string& path) {
  try {
    read_mesh(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

// A bad mesh file: its name, its bytes and what read_mesh's error must say.
struct BadFile {
  std::string name, bytes, expect;
};

// Each file, written into dir, gives an InputError naming it and the expected text.
void expect_read_errors(const fs::path& dir, const std::vector<BadFile>& files) {
  for (const BadFile& f : files) {
    spit(dir / f.name, f.bytes);
    const std::string message = error_of((dir / f.name).string());
    EXPECT_NE(message.find((dir / f.name).string()), std::string::npos) << f.name << ": " << message;
    EXPECT_NE(message.find(f.expect), std::string::npos) << f.name << ": " << message;
  }
}

void expect_same_positions(const TriangleMesh& a, const TriangleMesh& b) {
  ASSERT_EQ(a.positions.size(), b.positions.size());
  for (std::size_t i = 0; i < a.positions.size(); ++i)
    EXPECT_LE((a.positions[i] - b.positions[i]).norm(), 1e-6f) << "vertex " << i;
}

TEST(MeshIo, PlyRoundTripKeepsPositionsNormalsAndColours) {
  const fs::path dir = scratch("ply");
  const TriangleMesh m = small_mesh();
  write_mesh((dir / "m.ply").string(), m);
  EXPECT_NE(slurp(dir / "m.ply").find("format binary_little_endian"), std::string::npos);
  const TriangleMesh r = read_mesh((dir / "m.ply").string());
  expect_same_positions(m, r);
  EXPECT_EQ(r.triangles, m.triangles);
  ASSERT_EQ(r.normals.size(), m.normals.size());
  for (std::size_t i = 0; i < m.normals.size(); ++i)
    EXPECT_LE((r.normals[i] - m.normals[i]).norm(), 1e-6f);
  EXPECT_EQ(r.colors, m.colors);
}

TEST(MeshIo, VtpRoundTripKeepsPositionsNormalsAndColours) {
  const fs::path dir = scratch("vtp");
  const TriangleMesh m = small_mesh();
  write_mesh((dir / "m.vtp").string(), m);
  const TriangleMesh r = read_mesh((dir / "m.vtp").string());
  expect_same_positions(m, r);
  EXPECT_EQ(r.triangles, m.triangles);
  ASSERT_EQ(r.normals.size(), m.normals.size());
  for (std::size_t i = 0; i < m.normals.size(); ++i)
    EXPECT_LE((r.normals[i] - m.normals[i]).norm(), 1e-6f);
  EXPECT_EQ(r.colors, m.colors);
}

TEST(MeshIo, ObjAndOffRoundTripKeepPositionsAndTriangles) {
  const fs::path dir = scratch("obj_off");
  TriangleMesh m = small_mesh();
  for (const char* name : {"m.obj", "m.off"}) {
    SCOPED_TRACE(name);
    write_mesh((dir / name).string(), m);
    const TriangleMesh r = read_mesh((dir / name).string());
    expect_same_positions(m, r);
    EXPECT_EQ(r.triangles, m.triangles);
  }
  // Without attributes nothing is invented on the way back.
  m.normals.clear();
  m.colors.clear();
  write_mesh((dir / "plain.off").string(), m);
  const TriangleMesh r = read_mesh((dir / "plain.off").string());
  EXPECT_TRUE(r.normals.empty());
  EXPECT_TRUE(r.colors.empty());
}

TEST(MeshIo, StlRoundTripKeepsEveryTriangleCorner) {
  // STL stores corners per triangle; reading merges equal corners again, so
  // compare triangle by triangle, not vertex by vertex.
  const fs::path dir = scratch("stl");
  const TriangleMesh m = small_mesh();
  write_mesh((dir / "m.stl").string(), m);
  const TriangleMesh r = read_mesh((dir / "m.stl").string());
  EXPECT_EQ(r.positions.size(), m.positions.size());
  ASSERT_EQ(r.triangles.size(), m.triangles.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      EXPECT_LE((r.positions[r.triangles[t][k]] - m.positions[m.triangles[t][k]]).norm(), 1e-6f);
}

TEST(MeshIo, ReadsTheStanfordBunny) {
  const fs::path file = fs::path(SCAN2LOD_SHARED_DIR) / "data/bunny/reconstruction/bun_zipper.ply";
  if (!fs::exists(file)) GTEST_SKIP() << file << " not present";
  const TriangleMesh m = read_mesh(file.string());
  EXPECT_EQ(m.positions.size(), 35947u);
  EXPECT_EQ(m.triangles.size(), 69451u);
  // Metres: the bunny sits on y = 0.033 and is about 15 cm tall.
  const Aabb box = bounds(m.positions);
  EXPECT_NEAR(box.min.y(), 0.0330, 0.0005);
  EXPECT_NEAR(box.max.y(), 0.1873, 0.0005);
}

TEST(MeshIo, RangeGridPlyIsRejectedWithAHint) {
  const fs::path file = fs::path(SCAN2LOD_SHARED_DIR) / "data/bunny/data/bun000.ply";
  if (!fs::exists(file)) GTEST_SKIP() << file << " not present";
  EXPECT_NE(error_of(file.string()).find("range_grid"), std::string::npos);
}

TEST(MeshIo, PlyWithoutFacesSaysSo) {
  const fs::path dir = scratch("nofaces");
  spit(dir / "cloud.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
       "property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n");
  spit(dir / "empty_faces.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
       "property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n"
       "0 0 0\n1 0 0\n0 1 0\n");
  EXPECT_NE(error_of((dir / "cloud.ply").string()).find("has no faces"), std::string::npos);
  EXPECT_NE(error_of((dir / "empty_faces.ply").string()).find("has no faces"), std::string::npos);
}

TEST(MeshIo, MissingFileAndUnknownExtensionAreInputErrors) {
  const fs::path dir = scratch("missing");
  EXPECT_NE(error_of((dir / "nope.ply").string()).find("not found"), std::string::npos);
  spit(dir / "m.xyz", "0 0 0\n");
  EXPECT_NE(error_of((dir / "m.xyz").string()).find(".ply"), std::string::npos);
  EXPECT_THROW(write_mesh((dir / "m.xyz").string(), small_mesh()), InputError);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

TEST(MeshIo, GarbledPlyFilesAreInputErrors) {
  const fs::path dir = scratch("garbled_ply");
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const std::map<std::string, std::string> cases = {
      {"text_for_number.ply", header + "0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n"},
      {"index_out_of_range.ply", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"},
      {"negative_corner_count.ply", header + "0 0 0\n1 0 0\n0 1 0\n-1 0 1 2\n"},
      {"missing_face.ply", header + "0 0 0\n1 0 0\n0 1 0\n"},
      {"no_end_header.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"},
      {"not_ply.ply", "solid cube\nfacet normal 0 0 1\n"},
      {"empty.ply", ""},
      {"huge_count.ply",
       "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\nproperty float x\n"
       "property float y\nproperty float z\nelement face 1\n"
       "property list uchar int vertex_indices\nend_header\n\x01\x02"},
      {"nan_vertex.ply", header + "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n"},
  };
  for (const auto& [name, bytes] : cases) {
    SCOPED_TRACE(name);
    spit(dir / name, bytes);
    EXPECT_THROW(read_mesh((dir / name).string()), InputError);
  }
}

TEST(MeshIo, PlyHeaderWordsOpenMeshWouldReadOtherwiseAreInputErrors) {
  // Found by tests/fuzz/inputs_fuzzer: OpenMesh reads the PLY header word by
  // word, so a keyword after the format's version started a property before
  // any element, which it appended to an element that does not exist (SEGV).
  const fs::path dir = scratch("ply_header_words");
  const std::string body =
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const std::vector<BadFile> cases = {
      {"word_after_version.ply", "ply\nformat ascii 1.0 property uchar red\n" + body,
       "line 2: expected 'format FORMAT 1.0'"},
      {"glued_version.ply", "ply\nformat ascii 1property uchar red\n" + body, "line 2"},
      {"format_not_second.ply", "ply\ncomment x\nformat ascii 1.0\n" + body, "right after 'ply'"},
      {"keyword_in_obj_info.ply", "ply\nformat ascii 1.0\nobj_info end_header\n" + body,
       "obj_info holds a PLY keyword"},
      {"long_element.ply", "ply\nformat ascii 1.0\nelement vertex 3 property\n" + body.substr(17),
       "line 3: expected 'element NAME COUNT'"},
  };
  expect_read_errors(dir, cases);
  spit(dir / "fine.ply", "ply\nformat ascii 1.0\ncomment element property end_header\n" + body);
  EXPECT_EQ(try_read(dir / "fine.ply"), Outcome::read);
}

// Stanford's happy_stand scans carry 'bye' lines among their header lines. A
// line of no PLY keyword carries nothing a reader needs: the mesh reads as
// without it, and acquisition warns once, naming the file and the first line.
TEST(MeshIo, PlyHeaderLinesOfNoKeywordAreSkippedWithOneWarning) {
  const fs::path dir = scratch("ply_bye");
  auto with_bye = [](std::string bytes) {
    bytes.insert(bytes.find("element face"), "bye\n");
    bytes.insert(bytes.find('\n', bytes.find("format")) + 1, "bye\n");
    return bytes;
  };
  const std::string ascii_header =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string ascii_body = "0 0 0\n1 0 0\n0 1 0.25\n1 1 0\n3 0 1 2\n3 1 3 2\n";
  write_mesh((dir / "binary.ply").string(), small_mesh());
  spit(dir / "ascii.ply", ascii_header + ascii_body);
  for (const char* name : {"binary.ply", "ascii.ply"}) {
    SCOPED_TRACE(name);
    const fs::path plain = dir / name, odd = dir / (std::string("bye_") + name);
    spit(odd, with_bye(slurp(plain)));
    TriangleMesh a, b;
    ASSERT_EQ(try_read(plain, &a), Outcome::read);
    ASSERT_EQ(try_read(odd, &b), Outcome::read) << error_of(odd.string());
    ASSERT_EQ(a.positions.size(), b.positions.size());
    EXPECT_EQ(std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(Vec3f)), 0);
    EXPECT_EQ(a.triangles, b.triangles);
    EXPECT_EQ(a.colors, b.colors);
    AcquisitionReport plain_report, odd_report;
    load_oriented_points({plain.string()}, {}, &plain_report);
    load_oriented_points({odd.string()}, {}, &odd_report);
    EXPECT_TRUE(plain_report.warnings.empty());
    ASSERT_EQ(odd_report.warnings.size(), 1u);
    EXPECT_NE(odd_report.warnings[0].find(odd.string() + ": header line 3 ('bye') and 1 more"), std::string::npos)
        << odd_report.warnings[0];
  }
  // What was refused before still is, with such lines or without.
  const std::vector<BadFile> cases = {
      {"bye_holds_keyword.ply", "ply\nformat ascii 1.0\nbye element\n" + ascii_header.substr(21) + ascii_body,
       "line 3: a line of no PLY keyword holds one"},
      {"bye_before_format.ply", "ply\nbye\n" + ascii_header.substr(4) + ascii_body, "right after 'ply'"},
      {"bye_bad_element.ply", with_bye(ascii_header + ascii_body).replace(with_bye(ascii_header).find("vertex 4"), 8, "vertex four"),
       "expected 'element NAME COUNT'"},
      {"bye_short_body.ply", with_bye(ascii_header) + "0 0 0\n1 0 0\n0 1 0\n", "truncated"},
      {"bye_no_end_header.ply", "ply\nformat ascii 1.0\nbye\nelement vertex 4\nproperty float x\n", "end_header"},
  };
  expect_read_errors(dir, cases);
}

TEST(MeshIo, EveryTruncationOfABinaryPlyIsAnInputError) {
  const fs::path dir = scratch("truncated_ply");
  write_mesh((dir / "whole.ply").string(), small_mesh());
  const std::string whole = slurp(dir / "whole.ply");
  for (std::size_t size = 0; size < whole.size(); ++size) {
    spit(dir / "cut.ply", whole.substr(0, size));
    EXPECT_EQ(try_read(dir / "cut.ply"), Outcome::input_error) << "cut at byte " << size;
  }
}

TEST(MeshIo, GarbledOffFilesAreInputErrors) {
  const fs::path dir = scratch("garbled_off");
  const std::map<std::string, std::string> cases = {
      {"truncated.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n"},
      {"text_for_number.off", "OFF\n3 1 0\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n"},
      {"index_out_of_range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"},
      {"negative_corner_count.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n-1 0 1 2\n"},
      {"two_corners.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n"},
      {"huge_counts.off", "OFF\n2000000000 2000000000 0\n0 0 0\n"},
      {"no_counts.off", "OFF\n"},
      {"not_off.off", "ply\nformat ascii 1.0\n"},
  };
  for (const auto& [name, bytes] : cases) {
    SCOPED_TRACE(name);
    spit(dir / name, bytes);
    EXPECT_THROW(read_mesh((dir / name).string()), InputError);
  }
}

TEST(MeshIo, TruncatedOrBitFlippedFilesNeverCrash) {
  // ASCII cuts can land on a shorter but valid number, and flipped bytes can
  // stay valid; either way the reader must return a whole mesh or an InputError.
  // (.vtp is left out: VTK's XML reader has no such guarantee.)
  const fs::path dir = scratch("fuzz");
  std::mt19937 rng(7);
  for (const char* name : {"m.ply", "m.off", "m.obj", "m.stl"}) {
    SCOPED_TRACE(name);
    write_mesh((dir / name).string(), small_mesh());
    const std::string whole = slurp(dir / name);
    const fs::path bad = dir / (std::string("bad_") + name);
    for (std::size_t size = 0; size < whole.size(); size += 1 + whole.size() / 97) {
      spit(bad, whole.substr(0, size));
      TriangleMesh m;
      if (try_read(bad, &m) == Outcome::read) {
        for (const Triangle& t : m.triangles)
          for (int v : t) ASSERT_LT(std::size_t(v), m.positions.size());
      }
    }
    for (int trial = 0; trial < 200; ++trial) {
      std::string flipped = whole;
      for (int k = 0; k < 3; ++k)
        flipped[rng() % flipped.size()] = char(rng() % 256);
      spit(bad, flipped);
      TriangleMesh m;
      if (try_read(bad, &m) == Outcome::read) {
        for (const Triangle& t : m.triangles)
          for (int v : t) ASSERT_LT(std::size_t(v), m.positions.size());
      }
    }
  }
}

TEST(MeshIo, TruncatedVtpIsAnInputError) {
  const fs::path dir = scratch("truncated_vtp");
  write_mesh((dir / "whole.vtp").string(), small_mesh());
  const std::string whole = slurp(dir / "whole.vtp");
  const std::size_t data_end = whole.rfind("</AppendedData>");
  ASSERT_NE(data_end, std::string::npos);
  for (std::size_t size = 0; size < data_end; size += 1 + size / 8) {
    spit(dir / "cut.vtp", whole.substr(0, size));
    EXPECT_EQ(try_read(dir / "cut.vtp"), Outcome::input_error) << "cut at byte " << size;
  }
}

TEST(MeshIo, VtpCountsTheFileCannotHoldAreInputErrors) {
  // Found by tests/fuzz/inputs_fuzzer: VTK allocates by the XML's counts
  // before reading data (NumberOfPoints="400000000" asked for 4.8 GB) and
  // loops once per component over attribute names (a NumberOfComponents of
  // 2^31 hung for minutes). Both are now checked against the file's size.
  const fs::path dir = scratch("vtp_counts");
  write_mesh((dir / "whole.vtp").string(), small_mesh());
  const std::string whole = slurp(dir / "whole.vtp");
  auto edited = [&](const std::string& from, const std::string& to) {
    std::string s = whole;
    const std::size_t at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) s.replace(at, from.size(), to);
    return s;
  };
  const std::vector<BadFile> cases = {
      {"points.vtp", edited("NumberOfPoints=\"5\"", "NumberOfPoints=\"400000000\""),
       "Piece NumberOfPoints=400000000: more values than a file of"},
      {"polys.vtp", edited("NumberOfPolys=\"4\"", "NumberOfPolys=\"1000000000\""),
       "Piece NumberOfPolys=1000000000"},
      {"components.vtp",
       edited("NumberOfComponents=\"3\"", "NumberOfComponents=\"34444444444444444444444444\""),
       "expected 1 to 10000"},
      {"many_components.vtp", edited("NumberOfComponents=\"3\"", "NumberOfComponents=\"9000\""),
       "5 x 9000"},
  };
  expect_read_errors(dir, cases);
}

TEST(MeshIo, FailedWritesLeaveNoFileBehind) {
  const fs::path dir = scratch("failed_write");
  const fs::path missing = dir / "no" / "such" / "folder" / "m.ply";
  EXPECT_THROW(write_mesh(missing.string(), small_mesh()), InputError);
  EXPECT_FALSE(fs::exists(dir / "no"));

  TriangleMesh broken = small_mesh();
  broken.triangles.push_back({0, 1, 99});
  for (const char* name : {"m.ply", "m.vtp"}) {
    EXPECT_THROW(write_mesh((dir / name).string(), broken), InputError);
  }
  EXPECT_TRUE(fs::is_empty(dir)) << "a failed write left a file in " << dir;
}

TEST(MeshIo, WriteReplacesAnExistingFileWhole) {
  const fs::path dir = scratch("replace");
  TriangleMesh big = small_mesh();
  write_mesh((dir / "m.ply").string(), big);
  TriangleMesh small = small_mesh();
  small.triangles.resize(1);
  write_mesh((dir / "m.ply").string(), small);
  EXPECT_EQ(read_mesh((dir / "m.ply").string()).triangles.size(), 1u);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

}  // namespace
}  // namespace scan2lod
