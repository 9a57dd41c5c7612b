#include <scan2lod/io/gltf_file.h>

#include <scan2lod/core/error.h>
#include <scan2lod/io/atomic_file.h>
#include <scan2lod/io/file_extension.h>
#include <scan2lod/io/used_vertices.h>

// Debian's libtinygltf is built with nlohmann_json; no images are written,
// so stb is not needed.
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>

namespace scan2lod {

PositionGrid position_grid(const Aabb& box) {
  PositionGrid g;
  if (box.empty()) return g;
  g.centre = (box.min + box.max) * 0.5f;
  const float half = 0.5f * box.extent().maxCoeff();
  // Slightly over the half side, so that rounding never leaves [-32767, 32767].
  g.scale = half > 0 ? half * (1 + 1e-6f) : 1.f;
  return g;
}

namespace {

// The one binary buffer every view points into; views start 4-byte aligned,
// as vertex attributes require.
class BufferBuilder {
 public:
  explicit BufferBuilder(tinygltf::Model* model) : model_(model) {}

  // One allocation for the whole buffer: growing it view by view would copy
  // and fault in its pages again at every doubling.
  void reserve(std::size_t bytes) { buffer().reserve(bytes); }

  int add_view(const void* data, std::size_t size, std::size_t stride, int target) {
    std::vector<unsigned char>& bytes = buffer();
    const std::size_t offset = bytes.size();
    bytes.resize(offset + size);
    std::memcpy(bytes.data() + offset, data, size);
    bytes.resize((bytes.size() + 3) & ~std::size_t(3), 0);
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = offset;
    view.byteLength = size;
    view.byteStride = stride;
    view.target = target;
    model_->bufferViews.push_back(view);
    return int(model_->bufferViews.size()) - 1;
  }

  int add_accessor(int view, int component, int type, std::size_t count, bool normalized,
                   std::vector<double> min = {}, std::vector<double> max = {}) {
    tinygltf::Accessor a;
    a.bufferView = view;
    a.componentType = component;
    a.type = type;
    a.count = count;
    a.normalized = normalized;
    a.minValues = std::move(min);
    a.maxValues = std::move(max);
    model_->accessors.push_back(a);
    return int(model_->accessors.size()) - 1;
  }

 private:
  std::vector<unsigned char>& buffer() {
    if (model_->buffers.empty()) model_->buffers.emplace_back();
    return model_->buffers[0].data;
  }
  tinygltf::Model* model_;
};

// The node's translation: the file frame's origin, plus the quantization's
// centre (position = centre + scale * stored, so the node's T * S maps the
// stored values to origin + position); summed in double, as the JSON keeps it.
// None for float positions without an origin, as before origins existed.
std::vector<double> node_translation(const GltfOptions& options, const PositionGrid& q) {
  if (!options.quantize && options.origin == Vec3d::Zero()) return {};
  const Vec3d t = options.quantize ? Vec3d(options.origin + q.centre.cast<double>()) : options.origin;
  return {t.x(), t.y(), t.z()};
}

Vec3f unit_or_up(const Vec3f& n) {
  const float length = n.norm();
  return length > 1e-12f && std::isfinite(length) ? Vec3f(n / length) : Vec3f(0, 0, 1);
}

struct VertexAccessors {
  int position = -1, normal = -1, color = -1;
};

int add_positions(BufferBuilder& b, const std::vector<Vec3f>& p, const GltfOptions& options, const PositionGrid& q) {
  const std::size_t n = p.size();
  std::vector<double> min(3, 0), max(3, 0);
  if (!options.quantize) {
    const Aabb box = bounds(p);
    for (int k = 0; k < 3; ++k) min[k] = box.min[k], max[k] = box.max[k];
    const int view = b.add_view(p.data(), n * sizeof(Vec3f), 0, TINYGLTF_TARGET_ARRAY_BUFFER);
    return b.add_accessor(view, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, n, false, min, max);
  }
  std::vector<std::int16_t> packed(n * 4, 0);
  std::array<int, 3> lo{32767, 32767, 32767}, hi{-32767, -32767, -32767};
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      const float s = (p[i][k] - q.centre[k]) / q.scale * 32767.f;
      const int v = std::clamp(int(std::lround(s)), -32767, 32767);
      packed[i * 4 + k] = std::int16_t(v);
      lo[k] = std::min(lo[k], v);
      hi[k] = std::max(hi[k], v);
    }
  // Bounds of an integer accessor are its stored integers, normalized or not.
  for (int k = 0; k < 3; ++k) min[k] = lo[k], max[k] = hi[k];
  const int view = b.add_view(packed.data(), packed.size() * 2, 8, TINYGLTF_TARGET_ARRAY_BUFFER);
  return b.add_accessor(view, TINYGLTF_COMPONENT_TYPE_SHORT, TINYGLTF_TYPE_VEC3, n, true, min, max);
}

int add_normals(BufferBuilder& b, const std::vector<Vec3f>& normals, const GltfOptions& options) {
  const std::size_t n = normals.size();
  if (!options.quantize) {
    std::vector<Vec3f> unit(n);
    for (std::size_t i = 0; i < n; ++i) unit[i] = unit_or_up(normals[i]);
    const int view = b.add_view(unit.data(), n * sizeof(Vec3f), 0, TINYGLTF_TARGET_ARRAY_BUFFER);
    return b.add_accessor(view, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, n, false);
  }
  // 16 bits, not 8: 8-bit normals are off unit length by up to 1 %, which
  // validators flag and shading shows.
  std::vector<std::int16_t> packed(n * 4, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3f u = unit_or_up(normals[i]);
    for (int k = 0; k < 3; ++k) packed[i * 4 + k] = std::int16_t(std::lround(u[k] * 32767.f));
  }
  const int view = b.add_view(packed.data(), packed.size() * 2, 8, TINYGLTF_TARGET_ARRAY_BUFFER);
  return b.add_accessor(view, TINYGLTF_COMPONENT_TYPE_SHORT, TINYGLTF_TYPE_VEC3, n, true);
}

int add_colors(BufferBuilder& b, const std::vector<Rgb>& colors) {
  const std::size_t n = colors.size();
  std::vector<std::uint8_t> packed(n * 4, 255);
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) packed[i * 4 + k] = colors[i][k];
  const int view = b.add_view(packed.data(), packed.size(), 4, TINYGLTF_TARGET_ARRAY_BUFFER);
  return b.add_accessor(view, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_TYPE_VEC3, n, true);
}

int add_indices(BufferBuilder& b, const std::vector<Triangle>& triangles, std::size_t vertex_count) {
  const std::size_t n = triangles.size() * 3;
  // 65535 is the primitive-restart value of 16-bit indices: not a vertex.
  if (vertex_count <= 65535) {
    std::vector<std::uint16_t> packed(n);
    for (std::size_t t = 0; t < triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) packed[t * 3 + k] = std::uint16_t(triangles[t][k]);
    const int view = b.add_view(packed.data(), n * 2, 0, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    return b.add_accessor(view, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_SCALAR, n, false);
  }
  const int view = b.add_view(triangles.data(), n * 4, 0, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
  return b.add_accessor(view, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, n, false);
}

void check_chain(const std::string& path, const TriangleMesh& vertices, const std::vector<GltfLevel>& levels,
                 const GltfOptions& options) {
  if (!options.origin.allFinite()) throw InputError(path, "cannot write glTF: the origin is not a finite point");
  const std::size_t n = vertices.positions.size();
  if (n == 0) throw InputError(path, "cannot write glTF: the mesh has no vertices");
  if (levels.empty()) throw InputError(path, "cannot write glTF: no level to write");
  if (!vertices.normals.empty() && vertices.normals.size() != n)
    throw InputError(path, "cannot write glTF: " + std::to_string(vertices.normals.size()) + " normals for " +
                               std::to_string(n) + " vertices");
  if (!vertices.colors.empty() && vertices.colors.size() != n)
    throw InputError(path, "cannot write glTF: " + std::to_string(vertices.colors.size()) + " colours for " +
                               std::to_string(n) + " vertices");
  for (std::size_t i = 0; i < n; ++i)
    if (!vertices.positions[i].allFinite())
      throw InputError(path, "cannot write glTF: vertex " + std::to_string(i) + " is not finite");
  for (std::size_t l = 0; l < levels.size(); ++l) {
    const std::vector<Triangle>& tris = *levels[l].triangles;
    if (tris.empty()) throw InputError(path, "cannot write glTF: level '" + levels[l].name + "' has no triangles");
    for (const Triangle& t : tris)
      for (std::int32_t v : t)
        if (v < 0 || std::size_t(v) >= n)
          throw InputError(path, "cannot write glTF: level '" + levels[l].name + "' names vertex " +
                                     std::to_string(v) + " of " + std::to_string(n));
    if (l > 0 && levels[l].screen_coverage > levels[l - 1].screen_coverage)
      throw InputError(path, "cannot write glTF: screen coverage increases from level '" + levels[l - 1].name +
                                 "' to '" + levels[l].name + "'");
  }
}

tinygltf::Model build_model(const TriangleMesh& vertices, const std::vector<GltfLevel>& levels,
                            const GltfOptions& options) {
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = options.generator.empty() ? "scan2lod" : options.generator;
  BufferBuilder b(&model);
  std::size_t bytes = vertices.positions.size() * 32 + 64;  // the widest attributes, padded
  for (const GltfLevel& level : levels) bytes += level.triangles->size() * 12 + 4;
  b.reserve(bytes);
  const PositionGrid q = position_grid(bounds(vertices.positions));
  VertexAccessors va;
  va.position = add_positions(b, vertices.positions, options, q);
  if (!vertices.normals.empty()) va.normal = add_normals(b, vertices.normals, options);
  if (!vertices.colors.empty()) va.color = add_colors(b, vertices.colors);

  tinygltf::Material material;
  material.name = "scan";
  material.pbrMetallicRoughness.metallicFactor = 0;
  material.pbrMetallicRoughness.roughnessFactor = 0.8;
  model.materials.push_back(material);

  for (const GltfLevel& level : levels) {
    tinygltf::Primitive primitive;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    primitive.material = 0;
    primitive.attributes["POSITION"] = va.position;
    if (va.normal >= 0) primitive.attributes["NORMAL"] = va.normal;
    if (va.color >= 0) primitive.attributes["COLOR_0"] = va.color;
    primitive.indices = add_indices(b, *level.triangles, vertices.positions.size());
    tinygltf::Mesh mesh;
    mesh.name = level.name;
    mesh.primitives.push_back(primitive);
    model.meshes.push_back(mesh);

    tinygltf::Node node;
    node.name = level.name;
    node.mesh = int(model.meshes.size()) - 1;
    node.translation = node_translation(options, q);
    if (options.quantize) node.scale = {q.scale, q.scale, q.scale};
    model.nodes.push_back(node);
  }
  if (levels.size() > 1) {
    tinygltf::Value::Array ids, coverage;
    for (std::size_t l = 0; l < levels.size(); ++l) {
      if (l > 0) ids.emplace_back(int(l));
      coverage.emplace_back(std::clamp(levels[l].screen_coverage, 0.0, 1.0));
    }
    model.nodes[0].extensions["MSFT_lod"] = tinygltf::Value(tinygltf::Value::Object{{"ids", tinygltf::Value(ids)}});
    model.nodes[0].extras =
        tinygltf::Value(tinygltf::Value::Object{{"MSFT_screencoverage", tinygltf::Value(coverage)}});
    model.extensionsUsed.push_back("MSFT_lod");
  }
  if (options.quantize) {
    model.extensionsUsed.push_back("KHR_mesh_quantization");
    model.extensionsRequired.push_back("KHR_mesh_quantization");
  }
  tinygltf::Scene scene;
  scene.nodes = {0};  // the coarser levels are reached through MSFT_lod
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  return model;
}

}  // namespace

bool is_gltf_path(const std::string& path) {
  const std::string ext = lower_extension(path);
  return ext == ".glb" || ext == ".gltf";
}

void write_gltf_chain(const std::string& path, const TriangleMesh& vertices, const std::vector<GltfLevel>& levels,
                      const GltfOptions& options) {
  if (!is_gltf_path(path)) throw InputError(path, "expected a .glb or .gltf file name");
  check_chain(path, vertices, levels, options);
  const bool binary = lower_extension(path) == ".glb";
  // Vertices no level uses are left out (io/used_vertices.h).
  std::vector<const std::vector<Triangle>*> lists;
  for (const GltfLevel& level : levels) lists.push_back(level.triangles);
  std::optional<UsedVertices> used = drop_unused_vertices(vertices, lists);
  std::vector<GltfLevel> renumbered = levels;
  if (used)
    for (std::size_t l = 0; l < levels.size(); ++l) renumbered[l].triangles = &used->lists[l];
  const tinygltf::Model model = build_model(used ? used->vertices : vertices, renumbered, options);
  write_atomically(path, [&](const std::string& tmp) {
    // Straight into the file: a string in between would copy the buffer
    // twice more and fault in its pages.
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw InputError(path, "cannot create the file (does the folder exist?)");
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToStream(&model, out, !binary, binary))
      throw InputError(path, "tinygltf could not serialise the model");
    out.close();
    if (out.fail()) throw InputError(path, "writing glTF failed (disk full?)");
  });
}

void write_gltf(const std::string& path, const TriangleMesh& mesh, const GltfOptions& options) {
  write_gltf_chain(path, mesh, {GltfLevel{&mesh.triangles, "mesh", 0}}, options);
}

}  // namespace scan2lod
