// Outputs of a georeferenced input lie in the file's own frame: a LAS survey
// at UTM offsets, shifted to a local origin on input (acquisition/las_file.h),
// is shifted back on output (io/mesh_file.h, MeshWriteOptions::origin), so
// that the mesh written as PLY (double positions), OBJ, OFF, VTP or glTF (a
// node translation) lies on the survey's returns in the file's coordinates,
// within the file's 1 mm scale, read back by scan2lod and by Open3D; a model
// (.mco) keeps the origin, so `extract` and `export` do the same. Outputs of
// inputs without an origin are the bytes they were before.
#include <scan2lod/acquisition/las_file.h>
#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/core/error.h>
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/measure/surface_distance.h>
#include <scan2lod/pipeline/build_model.h>

#include "test_las_file.h"
#include "test_support.h"

#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <open3d/geometry/TriangleMesh.h>
#include <open3d/io/TriangleMeshIO.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

using namespace scan2lod;
using scan2lod::testing::CliRun;
using scan2lod::testing::LasFile;
using scan2lod::testing::las_bytes;
using scan2lod::testing::run_cli;
namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) { return scan2lod::testing::scratch_folder("las_output") / name; }

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// An airborne survey of a hill, as test_las.cpp's terrain: 120 x 120 returns
// 0.5 m apart over 60 m, on the 1 mm grid of a file offset to UTM-sized
// coordinates (`offset` plus 1 km east and 2 km north).
struct Survey {
  LasFile file;
  fs::path path;
  std::vector<Vec3d> returns;  // in the file's frame, as the records hold them
  Vec3d low, high;             // the header's bounds
};

Survey hill_survey(const std::string& name, const Vec3d& offset) {
  Survey s;
  s.file.format = 3;
  s.file.offset = offset;
  const int n = 120;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double x = 0.5 * i - 30, y = 0.5 * j - 30;
      const double z = 12.0 * std::exp(-(x * x + y * y) / 200.0) + 0.05 * x;
      s.file.records.push_back({std::int32_t(std::lround((x + 1000) / 0.001)),
                                std::int32_t(std::lround((y + 2000) / 0.001)), std::int32_t(std::lround(z / 0.001))});
      s.file.colors.push_back({std::uint16_t(i * 500), std::uint16_t(j * 500), 30000});
    }
  s.low = Vec3d::Constant(1e300), s.high = -s.low;
  for (const auto& r : s.file.records) {
    Vec3d p;
    for (int a = 0; a < 3; ++a) p[a] = r[std::size_t(a)] * s.file.scale[a] + s.file.offset[a];
    s.returns.push_back(p);
    s.low = s.low.cwiseMin(p), s.high = s.high.cwiseMax(p);
  }
  s.path = scratch(name);
  std::ofstream(s.path, std::ios::binary) << las_bytes(s.file);
  return s;
}

const Survey& utm_survey() {
  static const Survey s = hill_survey("hill_utm.las", Vec3d(500000, 5000000, 300));
  return s;
}

// How a mesh in the file's frame, `origin` + positions, lies against the
// survey: the returns' distances to it, and how far it reaches past the
// header's bounds (0 inside them).
struct Placement {
  DistanceStats returns_to_mesh;
  double past_bounds = 0;
};

Placement placement(const Survey& s, const TriangleMesh& mesh, const Vec3d& origin) {
  std::vector<Vec3f> returns;
  for (const Vec3d& p : s.returns) returns.push_back((p - origin).cast<float>());
  Placement out;
  out.returns_to_mesh = distance_stats(distances_to_surface(returns, mesh));
  for (const Vec3f& v : mesh.positions) {
    const Vec3d q = origin + v.cast<double>();
    out.past_bounds = std::max({out.past_bounds, (s.low - q).maxCoeff(), (q - s.high).maxCoeff()});
  }
  return out;
}

// The returns lie on the mesh within the 1 mm scale's order (the in-memory
// reconstruction's mean is 1 mm, test_las.cpp), and the mesh stays within a
// few 0.47 m cubes of the survey (reach 2.5 spacings: 1.49 m).
void expect_in_the_files_frame(const Survey& s, const TriangleMesh& mesh, const Vec3d& origin) {
  const Placement p = placement(s, mesh, origin);
  EXPECT_LT(p.returns_to_mesh.mean, 0.005);
  EXPECT_LT(p.returns_to_mesh.p95, 0.01);
  EXPECT_LT(p.past_bounds, 2.0);
}

std::string output_error(const CliRun& r) { return r.output.substr(0, 2000); }

fs::path validator_modules() { return fs::path(SCAN2LOD_BINARY_DIR) / "npm" / "node_modules"; }

// The Khronos glTF-Validator's report on `file` (tests/gltf/validate.mjs), or
// "" when node is not installed.
std::string validator_report(const fs::path& file) {
  if (std::system("node --version >/dev/null 2>&1") != 0) return "";
  return scan2lod::testing::run_shell("node " + std::string(SCAN2LOD_SOURCE_DIR) + "/tests/gltf/validate.mjs " +
                                      validator_modules().string() + " " + file.string() + " 2>&1")
      .output;
}

}  // namespace

// The case: `reconstruct` of a survey at (501 000, 5 002 000, 300 m)
// with a 1 mm scale, where a float's step is 0.5 m. Each format read back by
// scan2lod (about a local origin it chooses) lies on the returns.
TEST(LasOutput, ReconstructWritesEveryFormatInTheFilesFrame) {
  const Survey& s = utm_survey();
  const Vec3d las_origin = las_local_origin(read_las_header(s.path.string()));
  for (const std::string name : {"hill.ply", "hill.obj", "hill.off", "hill.vtp", "hill.glb", "hill.gltf", "f.glb"}) {
    SCOPED_TRACE(name);
    const fs::path out = scratch(name);
    const CliRun r = run_cli("reconstruct " + s.path.string() + " -r 128 -q -o " + out.string() +
                             (name == "f.glb" ? " --no-quantize" : ""));
    ASSERT_EQ(r.status, 0) << output_error(r);
    Vec3d origin;
    const TriangleMesh mesh = read_mesh(out.string(), &origin);
    EXPECT_GT(origin.y(), 4.9e6) << "floats cannot hold the file's frame: read about a local origin";
    ASSERT_GT(mesh.triangles.size(), 10000u);
    expect_in_the_files_frame(s, mesh, origin);
  }
  // PLY holds double positions; Open3D reads them as they are (its vertices
  // are doubles), in the file's frame.
  EXPECT_NE(slurp(scratch("hill.ply")).find("property double x\nproperty double y\nproperty double z\n"),
            std::string::npos);
  Vec3d origin;
  const TriangleMesh ours = read_mesh(scratch("hill.ply").string(), &origin);
  open3d::geometry::TriangleMesh o;
  ASSERT_TRUE(open3d::io::ReadTriangleMesh(scratch("hill.ply").string(), o));
  ASSERT_EQ(o.vertices_.size(), ours.positions.size());
  double worst = 0;
  for (std::size_t i = 0; i < o.vertices_.size(); ++i)
    worst = std::max(worst, (o.vertices_[i] - (origin + ours.positions[i].cast<double>())).cwiseAbs().maxCoeff());
  EXPECT_LT(worst, 1e-5);  // the float positions about the origin: 2e-6 at 30 m
  TriangleMesh theirs = ours;
  for (std::size_t i = 0; i < o.vertices_.size(); ++i) theirs.positions[i] = (o.vertices_[i] - origin).cast<float>();
  expect_in_the_files_frame(s, theirs, origin);
  // glTF: float positions under a node translation of the origin (and, by
  // default, the quantization's centre), which the JSON holds as a double.
  for (const char* name : {"hill.glb", "f.glb"}) {
    SCOPED_TRACE(name);
    tinygltf::Model model;
    tinygltf::TinyGLTF loader;
    std::string err, warn;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &err, &warn, scratch(name).string())) << err;
    ASSERT_EQ(model.nodes[0].translation.size(), 3u);
    const bool quantized = std::string(name) == "hill.glb";
    for (int k = 0; k < 3; ++k)
      if (quantized) EXPECT_NEAR(model.nodes[0].translation[std::size_t(k)], las_origin[k], 100.0);
      else EXPECT_EQ(model.nodes[0].translation[std::size_t(k)], las_origin[k]);  // bit for bit
    const std::string report = validator_report(scratch(name));
    if (!report.empty()) {
      EXPECT_NE(report.find("\"numErrors\":0,\"numWarnings\":0"), std::string::npos) << report;
    }
  }
}

// STL holds floats only: in the UTM frame they would move vertices by up to
// 0.25 m, so it is refused, naming the formats that keep the frame, and
// nothing is written. On a local grid (coordinates of a few km) floats hold it.
TEST(LasOutput, CompareMeasuresGeoreferencedMeshesInTheirFrame) {
  // A 10 m wall facing north at a UTM northing (floats step by 0.5 m
  // there), and the same wall 1 mm further north: compare reads both in
  // double and finds the millimetre.
  TriangleMesh wall;
  for (int i = 0; i <= 10; ++i)
    for (int k = 0; k <= 10; ++k) wall.positions.push_back(Vec3f(float(i), 0.f, float(k)));
  for (int i = 0; i < 10; ++i)
    for (int k = 0; k < 10; ++k) {
      const std::int32_t v = std::int32_t(11 * i + k);
      wall.triangles.push_back({v, v + 11, v + 1});
      wall.triangles.push_back({v + 1, v + 11, v + 12});
    }
  MeshWriteOptions near, far;
  near.origin = Vec3d(501000, 5002000, 300);
  far.origin = Vec3d(501000, 5002000.001, 300);
  write_mesh(scratch("wall.ply").string(), wall, near);
  write_mesh(scratch("wall_north.ply").string(), wall, far);
  const CliRun r = run_cli("compare " + scratch("wall_north.ply").string() + " " + scratch("wall.ply").string() + " --json");
  ASSERT_EQ(r.status, 0) << output_error(r);
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_NEAR(j.at("a_to_b").at("mean").get<double>(), 0.001, 1e-5);
  EXPECT_NEAR(j.at("b_to_a").at("max").get<double>(), 0.001, 1e-5);
}

TEST(LasOutput, StlIsWrittenOnlyWhereFloatsHoldTheFilesFrame) {
  const fs::path refused = scratch("hill.stl");
  const CliRun r = run_cli("reconstruct " + utm_survey().path.string() + " -r 128 -q -o " + refused.string());
  EXPECT_EQ(scan2lod::testing::exit_code(r), 1) << output_error(r);
  for (const char* words : {"hill.stl", "STL holds 32-bit floats only", "write .ply, .obj, .off, .vtp, .glb or .gltf"})
    EXPECT_NE(r.output.find(words), std::string::npos) << words << " in: " << output_error(r);
  EXPECT_FALSE(fs::exists(refused));

  const Survey local = hill_survey("hill_local.las", Vec3d::Zero());
  const fs::path written = scratch("local.stl");
  const CliRun w = run_cli("reconstruct " + local.path.string() + " -r 128 -q -o " + written.string());
  ASSERT_EQ(w.status, 0) << output_error(w);
  expect_in_the_files_frame(local, read_mesh(written.string()), Vec3d::Zero());
}

namespace {

// A model keeps the origin (.mco section ORGN), so that its levels come out
// in the file's frame: `extract` in each format, and `export` as a glTF
// chain and as a file per level.
void expect_model_outputs_in_the_files_frame(const Survey& s, const fs::path& model, const std::string& stem) {
  for (const std::string ext : {"ply", "obj", "glb"}) {
    SCOPED_TRACE("extract ." + ext);
    const fs::path out = scratch(stem + "_full." + ext);
    const CliRun r = run_cli("extract " + model.string() + " --percent 100 -q -o " + out.string());
    ASSERT_EQ(r.status, 0) << output_error(r);
    Vec3d origin;
    const TriangleMesh mesh = read_mesh(out.string(), &origin);
    expect_in_the_files_frame(s, mesh, origin);
  }
  const fs::path chain = scratch(stem + "_chain.glb");
  CliRun r = run_cli("export " + model.string() + " --levels 100,25 -q -o " + chain.string());
  ASSERT_EQ(r.status, 0) << output_error(r);
  Vec3d origin;
  expect_in_the_files_frame(s, read_mesh(chain.string(), &origin), origin);  // its finest level
  const std::string report = validator_report(chain);
  if (!report.empty()) {
    EXPECT_NE(report.find("\"numErrors\":0,\"numWarnings\":0"), std::string::npos) << report;
  }
  r = run_cli("export " + model.string() + " --levels 100,25 -q -o " + scratch(stem + "_level.ply").string());
  ASSERT_EQ(r.status, 0) << output_error(r);
  for (const char* level : {"_level_LOD0.ply", "_level_LOD1.ply"}) {
    SCOPED_TRACE(level);
    const TriangleMesh mesh = read_mesh(scratch(stem + level).string(), &origin);
    // A coarser level lies off the returns by its simplification, not by the frame.
    EXPECT_LT(placement(s, mesh, origin).returns_to_mesh.mean, 0.05);
    EXPECT_LT(placement(s, mesh, origin).past_bounds, 2.0);
  }
}

}  // namespace

TEST(LasOutput, AModelWithTheSurveysOriginExtractsAndExportsInTheFilesFrame) {
  const Survey& s = utm_survey();
  AcquisitionReport report;
  const OrientedPoints points = load_oriented_points({s.path.string()}, {}, &report);
  BuildOptions options;
  options.reconstruct.resolution = 128;
  LodModel model = build_model(points, nullptr, options);
  model.origin = report.origin;
  const fs::path path = scratch("hill_api.mco");
  save_model(path.string(), model);
  EXPECT_EQ(load_model(path.string()).origin, report.origin);
  // `info` shows the frame, to the bit in --json.
  const CliRun info = run_cli("info " + path.string() + " --json");
  ASSERT_EQ(info.status, 0) << output_error(info);
  const nlohmann::json j = nlohmann::json::parse(info.output);
  ASSERT_TRUE(j.contains("origin")) << info.output;
  for (int k = 0; k < 3; ++k) EXPECT_EQ(j["origin"][std::size_t(k)].get<double>(), report.origin[k]);
  EXPECT_NE(run_cli("info " + path.string()).output.find("origin ("), std::string::npos);
  expect_model_outputs_in_the_files_frame(s, path, "api");
}

// The same through `build`, which sets the model's origin from its inputs
// (pipeline/build_model.cpp).
TEST(LasOutput, BuildOfASurveyExtractsInTheFilesFrame) {
  const Survey& s = utm_survey();
  const fs::path model = scratch("hill.mco");
  const CliRun r = run_cli("build " + s.path.string() + " -r 128 -q -o " + model.string());
  ASSERT_EQ(r.status, 0) << output_error(r);
  ASSERT_EQ(load_model(model.string()).origin, las_local_origin(read_las_header(s.path.string())))
      << "build must keep its inputs' origin in the model (LodModel::origin)";
  expect_model_outputs_in_the_files_frame(s, model, "cli");
}

// Without an origin every writer writes the bytes it wrote before origins
// existed: the checksums below are of the files the writers of that version
// wrote for this mesh (XXH64, seed 0; sizes in bytes).
TEST(LasOutput, WithoutAnOriginEveryFormatWritesTheBytesItWroteBefore) {
  TriangleMesh m;  // a bumpy sphere, 13 x 16 samples, with normals, colours and one unused vertex
  const int rows = 12, cols = 16;
  for (int i = 0; i <= rows; ++i)
    for (int j = 0; j < cols; ++j) {
      const double theta = M_PI * i / rows, phi = 2 * M_PI * j / cols;
      const double radius = 1.37 + 0.05 * std::sin(3 * phi) * std::sin(2 * theta);
      const Vec3d n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
      m.positions.push_back((radius * n + Vec3d(0.25, -3.5, 12.125)).cast<float>());
      m.normals.push_back(n.cast<float>());
      m.colors.push_back(Rgb{std::uint8_t(i * 20), std::uint8_t(j * 15), std::uint8_t((i * j) % 256)});
    }
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) {
      const int a = i * cols + j, b = i * cols + (j + 1) % cols, c = a + cols, d = b + cols;
      m.triangles.push_back({a, c, b});
      m.triangles.push_back({b, c, d});
    }
  m.positions.push_back(Vec3f(9, 9, 9));
  m.normals.push_back(Vec3f(0, 0, 1));
  m.colors.push_back(Rgb{1, 2, 3});

  struct Before {
    const char* name;
    std::size_t size;
    std::uint64_t checksum;
  };
  const Before before[] = {{"m.ply", 10895, 0xda37819fa1970e13}, {"m.obj", 31219, 0x6d797554181a7119},
                           {"m.off", 20904, 0x501ab228ee21ed0a}, {"m.stl", 19284, 0xa6b6f1574053c604},
                           {"m.vtp", 14308, 0x157cad5843581eed}, {"m.glb", 7744, 0x0a43fffded319f8d},
                           {"m.gltf", 10848, 0x891822bb4cc5c09a}, {"f.glb", 9228, 0xd679c20ca720e374}};
  for (const Before& b : before) {
    SCOPED_TRACE(b.name);
    MeshWriteOptions options;
    options.quantize = b.name[0] != 'f';
    ASSERT_EQ(options.origin, Vec3d::Zero());
    write_mesh(scratch(b.name).string(), m, options);
    const std::string bytes = slurp(scratch(b.name));
    EXPECT_EQ(bytes.size(), b.size);
    EXPECT_EQ(model_checksum(bytes.data(), bytes.size()), b.checksum);
  }
}

// Every writer, given an origin, and read_mesh with an origin: the positions
// come back about a local origin as the file frame's doubles put them, each
// within a float step of the position written.
TEST(LasOutput, EveryFrameWriterReadsBackWithinAFloatStep) {
  TriangleMesh m;
  m.positions = {{0.125f, -1.5f, 2.25f}, {1.0078125f, -1.25f, 2.5f}, {0.3f, 0.7071068f, 2.0f}, {1.3333334f, 0.5f, 1.75f}};
  m.triangles = {{0, 1, 2}, {1, 3, 2}, {0, 2, 3}, {0, 3, 1}};
  m.normals.assign(4, Vec3f(0, 0, 1));
  m.colors = {Rgb{1, 2, 3}, Rgb{40, 50, 60}, Rgb{70, 80, 90}, Rgb{200, 210, 220}};
  MeshWriteOptions options;
  options.origin = Vec3d(500123.4567, 5001234.5678, 301.25);
  for (const std::string name : {"p.ply", "p.obj", "p.off", "p.vtp", "p.glb", "p.gltf", "f.glb"}) {
    SCOPED_TRACE(name);
    options.quantize = name[0] != 'f';
    write_mesh(scratch(name).string(), m, options);
    Vec3d origin;
    const TriangleMesh r = read_mesh(scratch(name).string(), &origin);
    ASSERT_EQ(r.positions.size(), m.positions.size());
    EXPECT_EQ(r.triangles, m.triangles);
    EXPECT_EQ(r.colors, m.colors);
    // Quantized glTF: half a step of 1/65534 of the longest side (2.2 m), and float rounding.
    const double step = bounds(m.positions).extent().maxCoeff() / 65534.0;
    const double tolerance = options.quantize && name.find(".gl") != std::string::npos ? step / 2 + 1e-6 : 1e-6;
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
      const Vec3d read = origin + r.positions[i].cast<double>(), written = options.origin + m.positions[i].cast<double>();
      EXPECT_LT((read - written).cwiseAbs().maxCoeff(), tolerance) << "vertex " << i;
    }
  }
}

// Double positions as other tools write them, ASCII or big-endian, with other
// elements and properties around them: read about a local origin, exactly as
// the file's doubles put them (to a float step about that origin).
TEST(LasOutput, DoublePlyFromOtherToolsReadsAboutALocalOrigin) {
  const std::vector<Vec3d> corners = {{500010.125, 5000020.5, 301.0625},
                                      {500011.25, 5000020.5, 301.0625},
                                      {500010.125, 5000021.75, 301.5},
                                      {500010.125, 5000020.5, 302.25}};
  const std::string faces[] = {"0 2 1", "0 1 3", "0 3 2", "1 2 3"};
  std::string ascii = "ply\nformat ascii 1.0\ncomment georeferenced\nelement camera 1\nproperty float f\n"
                      "element vertex 4\nproperty uchar quality\nproperty double x\nproperty double y\n"
                      "property double z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n7.5\n";
  for (const Vec3d& c : corners) {
    char line[128];
    std::snprintf(line, sizeof line, "9 %.17g %.17g %.17g\n", c.x(), c.y(), c.z());
    ascii += line;
  }
  for (const std::string& f : faces) ascii += "3 " + f + "\n";
  std::ofstream(scratch("ascii.ply"), std::ios::binary) << ascii;

  std::string big = "ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
                    "property double z\nproperty float nx\nelement face 4\nproperty list uchar int vertex_indices\n"
                    "end_header\n";
  auto put_big = [&big](const void* value, std::size_t size) {
    const char* bytes = static_cast<const char*>(value);
    for (std::size_t k = size; k-- > 0;) big += bytes[k];
  };
  for (const Vec3d& c : corners) {
    for (int k = 0; k < 3; ++k) put_big(&c[k], 8);
    const float n = 1;
    put_big(&n, 4);
  }
  for (const std::string& f : faces) {
    big += char(3);
    std::istringstream words(f);
    for (std::int32_t v; words >> v;) put_big(&v, 4);
  }
  std::ofstream(scratch("big.ply"), std::ios::binary) << big;

  for (const char* name : {"ascii.ply", "big.ply"}) {
    SCOPED_TRACE(name);
    Vec3d origin;
    const TriangleMesh m = read_mesh(scratch(name).string(), &origin);
    ASSERT_EQ(m.positions.size(), 4u);
    EXPECT_EQ(m.triangles.size(), 4u);
    EXPECT_GT(origin.y(), 4.9e6);
    for (std::size_t i = 0; i < 4; ++i)
      EXPECT_LT((origin + m.positions[i].cast<double>() - corners[i]).cwiseAbs().maxCoeff(), 1e-6) << "vertex " << i;
    // Without an origin, the floats of the file's frame: half a metre's step up north.
    const TriangleMesh floats = read_mesh(scratch(name).string());
    EXPECT_EQ(floats.positions[0].y(), float(corners[0].y()));
  }
}
