// Reading back what scan2lod writes: its glTF in every mode by read_mesh (and
// so by compare, build and reconstruct), glTF as other tools write it, and
// every mesh format `extract` writes by Open3D's reader, as users of Open3D
// will read them.
#include <scan2lod/core/error.h>
#include <scan2lod/io/mesh_file.h>
#include "test_support.h"

#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <open3d/Open3DConfig.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/io/TriangleMeshIO.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

namespace scan2lod {
namespace {

namespace fs = std::filesystem;
using testing::CliRun;
using testing::run_cli;

fs::path scratch(const std::string& name) { return testing::scratch_folder("read_back_" + name); }

// The bunny model's full level in every mesh format, extracted once per process.
struct Extracted {
  fs::path dir;
  TriangleMesh ply;  // the reference: binary PLY keeps floats exactly
  float step = 0;    // glTF position quantization step: longest side / 65534
};

const Extracted& bunny_outputs() {
  static const Extracted e = [] {
    Extracted x;
    x.dir = scratch("bunny");
    const std::string model = testing::bunny_model().string();
    for (const std::string name : {"m.ply", "m.obj", "m.off", "m.stl", "q.glb", "q.gltf"}) {
      const CliRun r = run_cli("extract " + model + " --percent 100 -q -o " + (x.dir / name).string());
      EXPECT_EQ(r.status, 0) << r.output;
    }
    for (const std::string name : {"f.glb", "f.gltf"}) {
      const CliRun r = run_cli("extract " + model + " --percent 100 --no-quantize -q -o " + (x.dir / name).string());
      EXPECT_EQ(r.status, 0) << r.output;
    }
    x.ply = read_mesh((x.dir / "m.ply").string());
    x.step = bounds(x.ply.positions).extent().maxCoeff() / 65534.f;
    return x;
  }();
  return e;
}

// Largest per-axis distance between corresponding triangle corners.
float corner_distance(const TriangleMesh& a, const TriangleMesh& b) {
  EXPECT_EQ(a.triangles.size(), b.triangles.size());
  float worst = 0;
  for (std::size_t t = 0; t < std::min(a.triangles.size(), b.triangles.size()); ++t)
    for (int k = 0; k < 3; ++k)
      worst = std::max(worst, (a.positions[a.triangles[t][k]] - b.positions[b.triangles[t][k]]).cwiseAbs().maxCoeff());
  return worst;
}

nlohmann::json compare_json(const fs::path& a, const fs::path& b) {
  const CliRun r = run_cli("compare " + a.string() + " " + b.string() + " --json", false);
  EXPECT_EQ(r.status, 0) << r.output;
  return nlohmann::json::parse(r.output, nullptr, false);
}

std::string error_of(const fs::path& path) {
  try {
    read_mesh(path.string());
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ReadBack, ExtractedGltfReadsAsThePlyInEveryMode) {
  const Extracted& e = bunny_outputs();
  ASSERT_GT(e.ply.triangles.size(), 10000u);
  for (const char* name : {"q.glb", "q.gltf", "f.glb", "f.gltf"}) {
    SCOPED_TRACE(name);
    const TriangleMesh g = read_mesh((e.dir / name).string());
    EXPECT_EQ(g.positions.size(), e.ply.positions.size());
    ASSERT_EQ(g.triangles.size(), e.ply.triangles.size());
    // Quantized corners land within half a step (plus float rounding of the
    // node transform); float ones are the same floats.
    const float tolerance = name[0] == 'q' ? 0.51f * e.step : 0.f;
    EXPECT_LE(corner_distance(g, e.ply), tolerance);
    ASSERT_EQ(g.normals.size(), e.ply.normals.size());
    float normal_error = 0;
    for (std::size_t i = 0; i < g.normals.size() && g.positions.size() == e.ply.positions.size(); ++i)
      normal_error = std::max(normal_error, (g.normals[i] - e.ply.normals[i].normalized()).norm());
    EXPECT_LE(normal_error, name[0] == 'q' ? 1e-4f : 1e-6f) << "16-bit normals are off by under 1e-4";
  }
}

TEST(ReadBack, CompareMeasuresAGlbAgainstItsPlyAsZero) {
  const Extracted& e = bunny_outputs();
  // Per axis at most half a step (and a little rounding), so at most
  // sqrt(3)/2 steps in all.
  for (const char* name : {"q.glb", "q.gltf"}) {
    SCOPED_TRACE(name);
    const nlohmann::json q = compare_json(e.dir / name, e.dir / "m.ply");
    ASSERT_TRUE(q.is_object());
    EXPECT_LE(q["a_to_b"]["max"].get<double>(), 0.9 * e.step);
    EXPECT_LE(q["b_to_a"]["max"].get<double>(), 0.9 * e.step);
    EXPECT_EQ(q["a"]["triangles"], q["b"]["triangles"]);
  }
  // Float glTF holds the same floats: only the ray caster's float rounding is left.
  const nlohmann::json f = compare_json(e.dir / "f.glb", e.dir / "m.ply");
  ASSERT_TRUE(f.is_object());
  EXPECT_LE(f["a_to_b"]["max"].get<double>(), 1e-6 * f["diagonal"].get<double>());
  EXPECT_LE(f["b_to_a"]["max"].get<double>(), 1e-6 * f["diagonal"].get<double>());
}

TEST(ReadBack, AnLodChainReadsAsItsFinestLevel) {
  const Extracted& e = bunny_outputs();
  const fs::path chain = e.dir / "chain.glb";
  const CliRun r = run_cli("export " + testing::bunny_model().string() + " --levels 100,25,5 -q -o " + chain.string());
  ASSERT_EQ(r.status, 0) << r.output;
  const TriangleMesh g = read_mesh(chain.string());
  EXPECT_EQ(g.triangles.size(), e.ply.triangles.size());
  EXPECT_LE(corner_distance(g, e.ply), 0.51f * e.step);
}

TEST(ReadBack, AMeshInputsFullDetailKeepsItsPositionsBitForBit) {
  // A mesh given to build is its own full detail: extracted at 100 %, every
  // position comes back with the bytes it had (a float round trip once moved
  // them all by up to 8e-9).
  const std::string zipper = std::string(SCAN2LOD_SHARED_DIR) + "/data/bunny/reconstruction/bun_zipper.ply";
  const fs::path dir = scratch("mesh_input");
  const CliRun built = run_cli("build " + zipper + " --structure clusters -q -o " + (dir / "z.mco").string());
  ASSERT_EQ(built.status, 0) << built.output;
  const CliRun extracted =
      run_cli("extract " + (dir / "z.mco").string() + " --percent 100 -q -o " + (dir / "z.ply").string());
  ASSERT_EQ(extracted.status, 0) << extracted.output;
  const TriangleMesh in = read_mesh(zipper), out = read_mesh((dir / "z.ply").string());
  // The bytes of the positions the triangles use (bun_zipper.ply has 1,113
  // that none does, which are not written), as a set.
  auto bytes = [](const TriangleMesh& m) {
    std::vector<std::uint8_t> used(m.positions.size(), 0);
    for (const Triangle& t : m.triangles)
      for (std::int32_t v : t) used[std::size_t(v)] = 1;
    std::vector<std::array<std::uint32_t, 3>> b;
    for (std::size_t v = 0; v < m.positions.size(); ++v)
      if (used[v]) {
        std::array<std::uint32_t, 3> x;
        std::memcpy(x.data(), m.positions[v].data(), sizeof x);
        b.push_back(x);
      }
    std::sort(b.begin(), b.end());
    return b;
  };
  ASSERT_EQ(out.triangles.size(), in.triangles.size());
  const auto a = bytes(in), b = bytes(out);
  ASSERT_EQ(b.size(), a.size());
  EXPECT_EQ(std::mismatch(a.begin(), a.end(), b.begin()).first - a.begin(), std::ptrdiff_t(a.size()));
}

TEST(ReadBack, BuildAndReconstructTakeGltfInputs) {
  const Extracted& e = bunny_outputs();
  const fs::path dir = scratch("inputs");
  // A cluster hierarchy over the mesh itself: its full level is the mesh.
  const CliRun b = run_cli("build " + (e.dir / "q.glb").string() + " --structure clusters -q -o " +
                           (dir / "g.mco").string());
  ASSERT_EQ(b.status, 0) << b.output;
  const CliRun x =
      run_cli("extract " + (dir / "g.mco").string() + " --percent 100 -q -o " + (dir / "full.ply").string());
  ASSERT_EQ(x.status, 0) << x.output;
  EXPECT_EQ(read_mesh((dir / "full.ply").string()).triangles.size(), e.ply.triangles.size());

  const CliRun rc = run_cli("reconstruct " + (e.dir / "f.gltf").string() + " -r 32 -q -o " + (dir / "r.ply").string());
  ASSERT_EQ(rc.status, 0) << rc.output;
  const nlohmann::json c = compare_json(dir / "r.ply", e.dir / "m.ply");
  ASSERT_TRUE(c.is_object());
  EXPECT_LT(c["a_to_b"]["mean"].get<double>(), 0.005 * c["diagonal"].get<double>());
}

// ---------------------------------------------------------------------------
// glTF as other tools write it, built with tinygltf: a node hierarchy with
// rotation, a mirroring matrix, indexed triangles, a strip, a fan, a sparse
// accessor, integer positions, a points primitive, a node outside the scene,
// and the buffer in a .bin file beside the .gltf.

class ModelBuilder {
 public:
  tinygltf::Model model;
  ModelBuilder() {
    model.asset.version = "2.0";
    model.buffers.emplace_back();
    model.buffers[0].uri = "other.bin";
  }
  template <typename T>
  int view(const std::vector<T>& data) {
    std::vector<unsigned char>& bytes = model.buffers[0].data;
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = bytes.size();
    v.byteLength = data.size() * sizeof(T);
    bytes.resize(bytes.size() + v.byteLength);
    std::memcpy(bytes.data() + v.byteOffset, data.data(), v.byteLength);
    bytes.resize((bytes.size() + 3) & ~std::size_t(3), 0);
    model.bufferViews.push_back(v);
    return int(model.bufferViews.size()) - 1;
  }
  // `per_element` values of `data` make one element, of which the first
  // `type`'s components are used; `stride` is the view's byteStride (0: tight).
  template <typename T>
  int accessor(const std::vector<T>& data, int component, int type, int per_element, bool normalized = false,
               std::size_t stride = 0) {
    tinygltf::Accessor a;
    a.bufferView = view(data);
    model.bufferViews.back().byteStride = stride;
    model.bufferViews.back().target =
        type == TINYGLTF_TYPE_SCALAR ? TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER : TINYGLTF_TARGET_ARRAY_BUFFER;
    a.componentType = component;
    a.type = type;
    a.count = data.size() / std::size_t(per_element);
    a.normalized = normalized;
    model.accessors.push_back(a);
    return int(model.accessors.size()) - 1;
  }
};

tinygltf::Model other_tools_model() {
  ModelBuilder b;
  // A unit quad with float normals and RGBA float colours.
  const int quad_p = b.accessor<float>({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                       TINYGLTF_TYPE_VEC3, 3);
  b.model.accessors[std::size_t(quad_p)].minValues = {0, 0, 0};
  b.model.accessors[std::size_t(quad_p)].maxValues = {1, 1, 0};
  const int quad_n = b.accessor<float>({0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                       TINYGLTF_TYPE_VEC3, 3);
  const int quad_c = b.accessor<float>({1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 0.5f, 1, 1, 1, 1},
                                       TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, 4);
  const int list = b.accessor<std::uint8_t>({0, 1, 2, 0, 2, 3}, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                                            TINYGLTF_TYPE_SCALAR, 1);
  const int strip = b.accessor<std::uint16_t>({0, 1, 3, 2}, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                                              TINYGLTF_TYPE_SCALAR, 1);
  tinygltf::Mesh quad;
  for (auto [mode, indices] : {std::pair{TINYGLTF_MODE_TRIANGLES, list}, std::pair{TINYGLTF_MODE_TRIANGLE_STRIP, strip},
                               std::pair{TINYGLTF_MODE_POINTS, -1}}) {
    tinygltf::Primitive p;
    p.mode = mode;
    p.indices = indices;
    p.attributes = {{"POSITION", quad_p}, {"NORMAL", quad_n}, {"COLOR_0", quad_c}};
    quad.primitives.push_back(p);
  }
  b.model.meshes.push_back(quad);

  // A fan of three triangles with plain SHORT positions (x100, padded to 8
  // bytes as vertex attributes must be), the last vertex moved by a sparse
  // accessor; normalized 8-bit normals and byte colours, padded to 4 bytes.
  const int fan_p = b.accessor<std::int16_t>({0, 0, 0, 0, 100, 0, 0, 0, 0, 100, 0, 0, -100, 0, 0, 0, 0, -100, 0, 0},
                                             TINYGLTF_COMPONENT_TYPE_SHORT, TINYGLTF_TYPE_VEC3, 4, false, 8);
  tinygltf::Accessor& moved = b.model.accessors[std::size_t(fan_p)];
  moved.minValues = {-100, -200, 0};  // as stored, after the sparse move
  moved.maxValues = {100, 100, 0};
  moved.sparse.isSparse = true;
  moved.sparse.count = 1;
  moved.sparse.indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
  moved.sparse.indices.bufferView = b.view<std::uint8_t>({4, 0, 0, 0});
  moved.sparse.indices.byteOffset = 0;
  moved.sparse.values.bufferView = b.view<std::int16_t>({0, -200, 0, 0});
  moved.sparse.values.byteOffset = 0;
  const int fan_n = b.accessor<std::int8_t>({0, 0, 127, 0, 0, 0, 127, 0, 0, 0, 127, 0, 0, 0, 127, 0, 0, 0, 127, 0},
                                            TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_TYPE_VEC3, 4, true, 4);
  const int fan_c = b.accessor<std::uint8_t>(
      {10, 20, 30, 0, 40, 50, 60, 0, 70, 80, 90, 0, 100, 110, 120, 0, 130, 140, 150, 0},
      TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_TYPE_VEC3, 4, true, 4);
  tinygltf::Mesh fan;
  tinygltf::Primitive p;
  p.mode = TINYGLTF_MODE_TRIANGLE_FAN;
  p.attributes = {{"POSITION", fan_p}, {"NORMAL", fan_n}, {"COLOR_0", fan_c}};
  fan.primitives.push_back(p);
  b.model.meshes.push_back(fan);

  const double h = std::sqrt(0.5);
  tinygltf::Node root, quad_node, fan_node, unused;
  root.translation = {10, 0, 0};
  root.rotation = {0, 0, h, h};  // 90 degrees about z
  root.children = {1, 2};
  quad_node.mesh = 0;
  quad_node.scale = {2, 2, 2};
  fan_node.mesh = 1;
  fan_node.matrix = {-0.01, 0, 0, 0, 0, 0.01, 0, 0, 0, 0, 0.01, 0, 0, 0, 0, 1};  // mirrors x
  unused.mesh = 0;
  b.model.nodes = {root, quad_node, fan_node, unused};
  tinygltf::Scene scene;
  scene.nodes = {0};
  b.model.scenes.push_back(scene);
  b.model.defaultScene = 0;
  b.model.extensionsUsed = {"KHR_mesh_quantization"};
  b.model.extensionsRequired = {"KHR_mesh_quantization"};
  return b.model;
}

void save(tinygltf::Model model, const fs::path& path) {
  tinygltf::TinyGLTF writer;
  const bool binary = path.extension() == ".glb";
  if (binary) model.buffers[0].uri.clear();  // the GLB's own binary chunk
  ASSERT_TRUE(writer.WriteGltfSceneToFile(&model, path.string(), false, binary, true, binary));
}

TEST(ReadBack, GltfFromOtherToolsReadsWithNodeTransformsStripsFansAndSparseData) {
  const fs::path dir = scratch("other");
  save(other_tools_model(), dir / "other.gltf");
  ASSERT_TRUE(fs::exists(dir / "other.bin"));
  const TriangleMesh m = read_mesh((dir / "other.gltf").string());

  // The quad's 4 vertices shared by its list and strip, then the fan's 5;
  // the points primitive and the node outside the scene are not read.
  ASSERT_EQ(m.positions.size(), 9u);
  ASSERT_EQ(m.triangles.size(), 2u + 2u + 3u);
  // Quad corner (1, 1, 0): scaled by 2, turned 90 degrees about z, moved 10 along x.
  EXPECT_LE((m.positions[2] - Vec3f(8, 2, 0)).norm(), 1e-5f);
  // Fan corner 4, (0, -2, 0) after the sparse move and the mirror, then turned and moved.
  EXPECT_LE((m.positions[4 + 4] - Vec3f(12, 0, 0)).norm(), 1e-5f);
  EXPECT_LE((m.positions[4 + 1] - Vec3f(10, -1, 0)).norm(), 1e-5f);
  // Every triangle faces +z: the strip's odd triangle and the mirrored fan
  // are wound back to counter-clockwise.
  for (const Triangle& t : m.triangles) {
    const Vec3f n = (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]);
    EXPECT_GT(n.z(), 0.f) << t[0] << " " << t[1] << " " << t[2];
  }
  EXPECT_EQ(m.triangles[2], (Triangle{0, 1, 3}));
  EXPECT_EQ(m.triangles[3], (Triangle{1, 2, 3}));
  ASSERT_EQ(m.normals.size(), 9u);
  for (const Vec3f& n : m.normals) EXPECT_LE((n - Vec3f(0, 0, 1)).norm(), 1e-6f);
  ASSERT_EQ(m.colors.size(), 9u);
  EXPECT_EQ(m.colors[0], (Rgb{255, 0, 0}));
  EXPECT_EQ(m.colors[2], (Rgb{0, 0, 255}));  // alpha dropped
  EXPECT_EQ(m.colors[4 + 3], (Rgb{100, 110, 120}));

  // The same scene as one .glb reads the same.
  save(other_tools_model(), dir / "other.glb");
  const TriangleMesh g = read_mesh((dir / "other.glb").string());
  EXPECT_EQ(g.triangles, m.triangles);
  EXPECT_EQ(corner_distance(g, m), 0.f);
}

TEST(ReadBack, AnExtensionThatChangesGeometryIsRefusedByName) {
  const fs::path dir = scratch("extensions");
  tinygltf::Model model = other_tools_model();
  model.extensionsUsed.push_back("KHR_draco_mesh_compression");
  model.extensionsRequired.push_back("KHR_draco_mesh_compression");
  save(model, dir / "draco.glb");
  const std::string message = error_of(dir / "draco.glb");
  EXPECT_NE(message.find((dir / "draco.glb").string() + ": "), std::string::npos) << message;
  EXPECT_NE(message.find("'KHR_draco_mesh_compression'"), std::string::npos) << message;
  const CliRun r = run_cli("compare " + (dir / "draco.glb").string() + " " + (dir / "draco.glb").string());
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("KHR_draco_mesh_compression"), std::string::npos) << r.output;

  // One that changes only how the surface looks is read through.
  model = other_tools_model();
  model.extensionsUsed.push_back("KHR_materials_unlit");
  model.extensionsRequired.push_back("KHR_materials_unlit");
  save(model, dir / "unlit.glb");
  EXPECT_EQ(read_mesh((dir / "unlit.glb").string()).triangles.size(), 7u);
}

TEST(ReadBack, DamagedGlbIsAnInputErrorNeverACrash) {
  const fs::path dir = scratch("damaged");
  const Extracted& e = bunny_outputs();
  std::mt19937 rng(11);
  for (const fs::path& source : {dir / "other.glb", e.dir / "q.glb"}) {
    SCOPED_TRACE(source.string());
    if (source.parent_path() == dir) save(other_tools_model(), source);
    std::ifstream in(source, std::ios::binary);
    const std::string whole((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const fs::path bad = dir / "bad.glb";
    auto outcome = [&](const std::string& bytes) {
      std::ofstream(bad, std::ios::binary) << bytes;
      try {
        const TriangleMesh m = read_mesh(bad.string());
        for (const Triangle& t : m.triangles)
          for (int v : t) ASSERT_LT(std::size_t(v), m.positions.size());
      } catch (const InputError&) {
      }
    };
    for (std::size_t size = 0; size < whole.size(); size += 1 + whole.size() / 61) outcome(whole.substr(0, size));
    // Flips in the JSON chunk (its length is the header's fourth word), where
    // they change structure, not just values.
    std::uint32_t json_length = 0;
    std::memcpy(&json_length, whole.data() + 12, 4);
    const std::size_t json_end = std::min<std::size_t>(whole.size(), 20 + json_length);
    for (int trial = 0; trial < 150; ++trial) {
      std::string flipped = whole;
      for (int k = 0; k < 2; ++k) flipped[rng() % json_end] = char(rng() % 256);
      outcome(flipped);
    }
  }
}

// ---------------------------------------------------------------------------
// OFF colours, and Open3D reading what scan2lod writes.

TriangleMesh coloured_tetrahedron(bool normals) {
  TriangleMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  m.colors = {{255, 0, 0}, {0, 128, 0}, {0, 0, 7}, {12, 34, 56}};
  if (normals)
    for (const Vec3f& p : m.positions) m.normals.push_back((p - Vec3f::Constant(0.25f)).normalized());
  return m;
}

// The numbers on the first vertex line of an ASCII OFF.
std::size_t first_vertex_values(const fs::path& off) {
  std::ifstream in(off);
  std::string line;
  std::getline(in, line);  // the keyword
  std::getline(in, line);  // the counts
  std::getline(in, line);
  std::istringstream words(line);
  std::size_t n = 0;
  for (double v; words >> v;) ++n;
  return n;
}

TEST(ReadBack, ColouredOffIsWrittenAsRgbaAndReadWithThreeOrFourValues) {
  const fs::path dir = scratch("off");
  for (bool normals : {false, true}) {
    SCOPED_TRACE(normals ? "with normals" : "without normals");
    const TriangleMesh m = coloured_tetrahedron(normals);
    const fs::path path = dir / (normals ? "cn.off" : "c.off");
    write_mesh(path.string(), m);
    EXPECT_EQ(first_vertex_values(path), 3u + (normals ? 3u : 0u) + 4u) << "position, normal, RGBA";
    EXPECT_EQ(read_mesh(path.string()).colors, m.colors);

    open3d::geometry::TriangleMesh o;
    ASSERT_TRUE(open3d::io::ReadTriangleMesh(path.string(), o));
    ASSERT_EQ(o.vertex_colors_.size(), 4u);
    for (std::size_t i = 0; i < 4; ++i)
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(o.vertex_colors_[i][k], m.colors[i][k] / 255.0, 1e-6);
    EXPECT_EQ(o.HasVertexNormals(), normals);
  }
  // Three colour values, as scan2lod wrote them before, still read.
  std::ofstream(dir / "rgb.off") << "COFF\n4 4 0\n0 0 0 255 0 0\n1 0 0 0 128 0\n0 1 0 0 0 7\n0 0 1 12 34 56\n"
                                    "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  EXPECT_EQ(read_mesh((dir / "rgb.off").string()).colors, coloured_tetrahedron(false).colors);
}

std::size_t distinct_positions(const open3d::geometry::TriangleMesh& m) {
  std::vector<std::array<double, 3>> p;
  for (const Eigen::Vector3d& v : m.vertices_) p.push_back({v.x(), v.y(), v.z()});
  std::sort(p.begin(), p.end());
  return std::size_t(std::unique(p.begin(), p.end()) - p.begin());
}

TEST(ReadBack, Open3DReadsEveryMeshFormatExtractWrites) {
  const Extracted& e = bunny_outputs();
  const std::size_t triangles = e.ply.triangles.size(), vertices = e.ply.positions.size();
  const Aabb box = bounds(e.ply.positions);
  for (const char* name : {"m.ply", "m.obj", "m.off", "m.stl", "f.glb"}) {
    SCOPED_TRACE(name);
    open3d::geometry::TriangleMesh o;
    ASSERT_TRUE(open3d::io::ReadTriangleMesh((e.dir / name).string(), o));
    EXPECT_EQ(o.triangles_.size(), triangles);
    // STL stores three corners per triangle, which Open3D joins only where
    // position and facet normal agree: count the distinct positions instead.
    EXPECT_EQ(std::string(name) == "m.stl" ? distinct_positions(o) : o.vertices_.size(), vertices);
    const Eigen::Vector3d lo = o.GetMinBound(), hi = o.GetMaxBound();
    EXPECT_LE((lo.cast<float>() - box.min).norm(), 1e-6f * box.extent().norm());
    EXPECT_LE((hi.cast<float>() - box.max).norm(), 1e-6f * box.extent().norm());
  }
}

// Why the README tells Open3D users to pass --no-quantize: Open3D up to 0.18
// ignores extensionsRequired and reads the normalized 16-bit positions of the
// default .glb as if they were floats, without a word (0.16.1: coordinates
// up to 3e38 for a bunny 0.16 wide).
TEST(ReadBack, Open3DUpTo018MisreadsTheQuantizedGlb) {
  if (OPEN3D_VERSION_MAJOR > 0 || OPEN3D_VERSION_MINOR > 18) GTEST_SKIP() << "Open3D " << OPEN3D_VERSION;
  const Extracted& e = bunny_outputs();
  open3d::geometry::TriangleMesh o;
  ASSERT_TRUE(open3d::io::ReadTriangleMesh((e.dir / "q.glb").string(), o)) << "Open3D now refuses it";
  const Aabb box = bounds(e.ply.positions);
  const bool right = o.vertices_.size() == e.ply.positions.size() &&
                     (o.GetMinBound().cast<float>() - box.min).norm() <= 1e-3f * box.extent().norm() &&
                     (o.GetMaxBound().cast<float>() - box.max).norm() <= 1e-3f * box.extent().norm();
  EXPECT_FALSE(right) << "Open3D " << OPEN3D_VERSION << " reads quantized glTF: update README.md";
}

}  // namespace
}  // namespace scan2lod
