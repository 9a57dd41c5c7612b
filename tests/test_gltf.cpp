// glTF output: every file is checked by the Khronos glTF-Validator (npm
// gltf-validator, installed by scripts/build.sh) and read back by tinygltf.
#include <scan2lod/core/error.h>
#include <scan2lod/io/gltf_file.h>
#include <scan2lod/io/mesh_file.h>
#include "test_shapes.h"
#include "test_support.h"

#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <open3d/geometry/TriangleMesh.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace scan2lod {
namespace {

namespace fs = std::filesystem;
using testing::CliRun;
using testing::run_cli;
using testing::scratch_folder;

fs::path validator_modules() { return fs::path(SCAN2LOD_BINARY_DIR) / "npm" / "node_modules"; }

// Runs the validator on `files`; skips the test when node is missing, fails
// it when node is there but the validator was not installed.
CliRun validate(const std::vector<fs::path>& files) {
  CliRun r{-1, ""};
  if (std::system("node --version >/dev/null 2>&1") != 0) return r;
  std::string command = "node " + std::string(SCAN2LOD_SOURCE_DIR) + "/tests/gltf/validate.mjs " +
                        validator_modules().string();
  for (const fs::path& f : files) command += " " + f.string();
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  char buffer[4096];
  std::size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) r.output.append(buffer, n);
  r.status = pclose(pipe);
  return r;
}

#define EXPECT_VALID_GLTF(...)                                                                              \
  do {                                                                                                      \
    if (std::system("node --version >/dev/null 2>&1") != 0) GTEST_SKIP() << "node is not installed";       \
    ASSERT_TRUE(fs::exists(validator_modules() / "gltf-validator"))                                        \
        << "node is here but the validator is not: run scripts/build.sh deps";                              \
    const CliRun v = validate({__VA_ARGS__});                                                               \
    EXPECT_EQ(v.status, 0) << v.output;                                                                     \
    EXPECT_NE(v.output.find("\"numErrors\":0,\"numWarnings\":0"), std::string::npos) << v.output;          \
  } while (0)

tinygltf::Model load(const fs::path& path) {
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  const bool ok = path.extension() == ".glb" ? loader.LoadBinaryFromFile(&model, &err, &warn, path.string())
                                             : loader.LoadASCIIFromFile(&model, &err, &warn, path.string());
  EXPECT_TRUE(ok) << err;
  return model;
}

// POSITION of a primitive in world space (node transform and normalization applied).
std::vector<Vec3f> positions_of(const tinygltf::Model& m, const tinygltf::Node& node) {
  const tinygltf::Primitive& p = m.meshes[std::size_t(node.mesh)].primitives[0];
  const tinygltf::Accessor& a = m.accessors[std::size_t(p.attributes.at("POSITION"))];
  const tinygltf::BufferView& v = m.bufferViews[std::size_t(a.bufferView)];
  const unsigned char* base = m.buffers[0].data.data() + v.byteOffset + a.byteOffset;
  const std::size_t stride = std::size_t(a.ByteStride(v));
  Vec3f t = Vec3f::Zero(), s = Vec3f::Ones();
  if (!node.translation.empty()) t = Vec3f(float(node.translation[0]), float(node.translation[1]), float(node.translation[2]));
  if (!node.scale.empty()) s = Vec3f(float(node.scale[0]), float(node.scale[1]), float(node.scale[2]));
  std::vector<Vec3f> out(a.count);
  for (std::size_t i = 0; i < a.count; ++i) {
    Vec3f q;
    for (int k = 0; k < 3; ++k) {
      if (a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT) {
        std::memcpy(&q[k], base + i * stride + std::size_t(k) * 4, 4);
      } else {
        std::int16_t raw;
        std::memcpy(&raw, base + i * stride + std::size_t(k) * 2, 2);
        q[k] = std::max(-1.f, float(raw) / 32767.f);
      }
    }
    out[i] = q.cwiseProduct(s) + t;
  }
  return out;
}

std::size_t index_count(const tinygltf::Model& m, const tinygltf::Node& node) {
  return m.accessors[std::size_t(m.meshes[std::size_t(node.mesh)].primitives[0].indices)].count;
}

TEST(Gltf, OneLevelIsValidBinaryAndText) {
  const fs::path dir = scratch_folder("gltf_single");
  const fs::path glb = dir / "level.glb", gltf = dir / "level.gltf", plain = dir / "level_float.glb";
  const std::string model = testing::bunny_model().string();
  for (const auto& [out, extra] : {std::pair{glb, ""}, std::pair{gltf, ""}}) {
    const CliRun r = run_cli("extract " + model + " --triangles 5000 -o " + out.string() + " -q" + extra);
    ASSERT_EQ(r.status, 0) << r.output;
  }
  const CliRun r = run_cli("extract " + model + " --triangles 5000 --no-quantize -o " + plain.string() + " -q");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_VALID_GLTF(glb, gltf, plain);

  // Quantized positions land within one step (1/32767 of the half side) of the floats.
  const tinygltf::Model q = load(glb), f = load(plain);
  ASSERT_EQ(q.nodes.size(), 1u);
  const std::vector<Vec3f> pq = positions_of(q, q.nodes[0]), pf = positions_of(f, f.nodes[0]);
  ASSERT_EQ(pq.size(), pf.size());
  const float step = float(q.nodes[0].scale[0]) / 32767.f;
  float worst = 0;
  for (std::size_t i = 0; i < pq.size(); ++i) worst = std::max(worst, (pq[i] - pf[i]).cwiseAbs().maxCoeff());
  EXPECT_LE(worst, step * 0.51f);
  EXPECT_LE(index_count(q, q.nodes[0]), 3u * 5500u) << "within 10 % of the budget";
  EXPECT_LT(fs::file_size(glb), fs::file_size(plain));
}

class GltfChain : public ::testing::TestWithParam<std::string> {};

TEST_P(GltfChain, FourLevelsAreOneValidFileSmallerThanFourPlys) {
  const std::string structure = GetParam();
  const fs::path dir = scratch_folder("gltf_chain_" + structure);
  const std::string model = testing::bunny_model().string();
  const fs::path glb = dir / "chain.glb";
  const CliRun r = run_cli("export " + model + " --structure " + structure + " --levels 100,25,5,1 --json -o " +
                           glb.string());
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  ASSERT_EQ(j["levels"].size(), 4u);
  EXPECT_VALID_GLTF(glb);

  const tinygltf::Model m = load(glb);
  ASSERT_EQ(m.nodes.size(), 4u);
  ASSERT_EQ(m.scenes[0].nodes, std::vector<int>{0});
  const tinygltf::Value& ids = m.nodes[0].extensions.at("MSFT_lod").Get("ids");
  ASSERT_EQ(ids.ArrayLen(), 3u);
  const tinygltf::Value& coverage = m.nodes[0].extras.Get("MSFT_screencoverage");
  ASSERT_EQ(coverage.ArrayLen(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    const tinygltf::Node& node = m.nodes[std::size_t(i == 0 ? 0 : ids.Get(int(i - 1)).GetNumberAsInt())];
    EXPECT_EQ(index_count(m, node), 3 * j["levels"][i]["triangles"].get<std::size_t>());
    if (i > 0) {
      EXPECT_LE(coverage.Get(int(i)).GetNumberAsDouble(), coverage.Get(int(i - 1)).GetNumberAsDouble());
    }
  }
  EXPECT_EQ(coverage.Get(3).GetNumberAsDouble(), 0.0);
  EXPECT_GT(coverage.Get(0).GetNumberAsDouble(), 0.0);
  // Triangle counts fall along the chain.
  for (std::size_t i = 1; i < 4; ++i)
    EXPECT_LT(j["levels"][i]["triangles"].get<std::size_t>(), j["levels"][i - 1]["triangles"].get<std::size_t>());

  // The same levels as separate binary PLYs take more room.
  const fs::path ply = dir / "level.ply";
  const CliRun p = run_cli("export " + model + " --structure " + structure + " --levels 100,25,5,1 -q -o " +
                           ply.string());
  ASSERT_EQ(p.status, 0) << p.output;
  std::uintmax_t plys = 0;
  for (int i = 0; i < 4; ++i) plys += fs::file_size(dir / ("level_LOD" + std::to_string(i) + ".ply"));
  EXPECT_LT(fs::file_size(glb), plys);
}

INSTANTIATE_TEST_SUITE_P(Structures, GltfChain, ::testing::Values("clusters", "octree"));

TEST(Gltf, ColouredVirtualScanKeepsItsColours) {
  const fs::path dir = scratch_folder("gltf_colour");
  open3d::geometry::TriangleMesh sphere = *open3d::geometry::TriangleMesh::CreateSphere(1.0, 40);
  TriangleMesh mesh = testing::from_open3d(sphere);
  for (const Vec3f& p : mesh.positions)
    mesh.colors.push_back({std::uint8_t(std::lround(127.5f * (p.z() + 1.f))), 40, 200});
  write_mesh((dir / "coloured.ply").string(), mesh);
  CliRun r = run_cli("scan " + (dir / "coloured.ply").string() + " -o " + (dir / "scans").string() + " -q");
  ASSERT_EQ(r.status, 0) << r.output;
  const fs::path glb = dir / "coloured.glb";
  r = run_cli("reconstruct " + (dir / "scans" / "scans.conf").string() + " -r 64 -q -o " + glb.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_VALID_GLTF(glb);

  const tinygltf::Model m = load(glb);
  const tinygltf::Primitive& p = m.meshes[0].primitives[0];
  ASSERT_EQ(p.attributes.count("COLOR_0"), 1u);
  ASSERT_EQ(p.attributes.count("NORMAL"), 1u);
  // Colours follow height: red = 127.5 (z + 1) within a few levels.
  const std::vector<Vec3f> pos = positions_of(m, m.nodes[0]);
  const tinygltf::Accessor& a = m.accessors[std::size_t(p.attributes.at("COLOR_0"))];
  const tinygltf::BufferView& v = m.bufferViews[std::size_t(a.bufferView)];
  double worst = 0;
  for (std::size_t i = 0; i < a.count; ++i) {
    const unsigned char* c = m.buffers[0].data.data() + v.byteOffset + i * std::size_t(a.ByteStride(v));
    worst = std::max(worst, std::abs(double(c[0]) - 127.5 * (pos[i].z() + 1.0)));
    EXPECT_EQ(c[2], 200);
  }
  EXPECT_LT(worst, 12.0);
}

TEST(Gltf, EmptyOrBrokenInputIsRefusedAndWritesNothing) {
  const fs::path dir = scratch_folder("gltf_bad");
  TriangleMesh empty;
  empty.positions = {Vec3f(0, 0, 0)};
  EXPECT_THROW(write_gltf((dir / "e.glb").string(), empty), InputError);
  TriangleMesh bad = empty;
  bad.triangles = {{0, 0, 5}};
  EXPECT_THROW(write_gltf((dir / "b.glb").string(), bad), InputError);
  EXPECT_THROW(write_gltf((dir / "b.txt").string(), bad), InputError);
  EXPECT_FALSE(fs::exists(dir / "e.glb"));
  EXPECT_FALSE(fs::exists(dir / "b.glb"));
  EXPECT_TRUE(fs::is_empty(dir));
}

}  // namespace
}  // namespace scan2lod
