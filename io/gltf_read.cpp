#include <scan2lod/io/gltf_read.h>

#include <scan2lod/core/error.h>
#include <scan2lod/io/local_origin.h>

// As in gltf_file.cpp: Debian's shared libtinygltf holds the implementation;
// images are never decoded here, so stb is not needed.
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <tuple>
#include <vector>

namespace scan2lod {
namespace {

std::string first_line(const std::string& s) {
  std::string line = s.substr(0, s.find('\n'));
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
  return line;
}

// Only the geometry is read, so extensions that change how a surface looks,
// never where it is, can be required without harm.
bool changes_only_appearance(const std::string& extension) {
  for (const char* prefix : {"KHR_materials_", "KHR_texture_", "EXT_texture_", "MSFT_texture_"})
    if (extension.rfind(prefix, 0) == 0) return true;
  return extension == "KHR_lights_punctual" || extension == "MSFT_lod";
}

bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                void*) {
  return true;
}

tinygltf::Model load_model(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::file_size(path, ec) == 0 && !ec) throw InputError(path, "file is empty, expected glTF");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open the file for reading");
  char magic[4] = {};
  in.read(magic, 4);
  // By content: a .gltf that is really GLB (or the reverse) still reads.
  const bool binary = in.gcount() == 4 && std::memcmp(magic, "glTF", 4) == 0;
  in.close();

  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&skip_image, nullptr);
  std::string err, warn;
  bool ok = false;
  try {
    ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, path)
                : loader.LoadASCIIFromFile(&model, &err, &warn, path);
  } catch (const std::exception& e) {
    err = e.what();
  }
  if (!ok)
    throw InputError(path, std::string("not a readable glTF ") + (binary ? "binary" : "JSON") +
                               " file: " + (err.empty() ? "tinygltf gave no reason" : first_line(err)));
  return model;
}

void check_required_extensions(const std::string& path, const tinygltf::Model& model) {
  for (const std::string& extension : model.extensionsRequired)
    if (extension != "KHR_mesh_quantization" && !changes_only_appearance(extension))
      throw InputError(path, "requires the glTF extension '" + extension +
                                 "', which scan2lod cannot read (it reads KHR_mesh_quantization and ignores "
                                 "extensions for materials, textures and lights); export the file without it");
}

// ---------------------------------------------------------------------------
// Accessors: typed, strided, possibly sparse views of the buffers.

int component_size(int component_type) {
  switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
  }
}

const char* component_name(int component_type) {
  switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: return "BYTE";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return "UNSIGNED_BYTE";
    case TINYGLTF_COMPONENT_TYPE_SHORT: return "SHORT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return "UNSIGNED_SHORT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return "UNSIGNED_INT";
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return "FLOAT";
    default: return "an unknown component type";
  }
}

int type_components(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    default: return 0;  // matrices: no attribute read here has them
  }
}

const char* type_name(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return "SCALAR";
    case TINYGLTF_TYPE_VEC2: return "VEC2";
    case TINYGLTF_TYPE_VEC3: return "VEC3";
    case TINYGLTF_TYPE_VEC4: return "VEC4";
    default: return "MAT2, MAT3, MAT4 or unknown";
  }
}

// One stored component as the accessor defines it (glTF 2.0, §3.11: normalized
// signed values map to max(c / (2^(b-1) - 1), -1), unsigned ones to c / (2^b - 1)).
double decode(const unsigned char* p, int component_type, bool normalized) {
  switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      std::int8_t v;
      std::memcpy(&v, p, 1);
      return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0 : p[0];
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      std::int16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      std::uint16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      std::uint32_t v;
      std::memcpy(&v, p, 4);
      return v;
    }
    default: {
      float v;
      std::memcpy(&v, p, 4);
      return v;
    }
  }
}

// What an attribute may be stored as.
struct AccessorRule {
  const char* role;        // "POSITION", "indices", ... for messages
  std::vector<int> types;  // TINYGLTF_TYPE_*
  bool floats;             // FLOAT allowed
  std::vector<int> normalized, plain;  // integer component types allowed normalized, not normalized
};

class AccessorReader {
 public:
  AccessorReader(const std::string& path, const tinygltf::Model& model) : path_(path), model_(model) {}

  // The element count of accessor `index` once check() has passed.
  std::size_t count(int index, const AccessorRule& rule, const std::string& where) const {
    check(index, rule, where);
    return accessor(index, where).count;
  }

  // Accessor `index` as count x components values, checked against `rule`.
  template <typename T>
  std::vector<T> read(int index, const AccessorRule& rule, const std::string& where, int* components) const {
    const unsigned char* base = check(index, rule, where);
    const tinygltf::Accessor& a = accessor(index, where);
    const std::string what = where + ": " + rule.role + " accessor " + std::to_string(index);
    *components = type_components(a.type);
    const int n = *components;
    const std::size_t c = std::size_t(component_size(a.componentType));
    const std::size_t element = c * std::size_t(n);
    const tinygltf::BufferView& view = model_.bufferViews[std::size_t(a.bufferView)];
    const std::size_t stride = view.byteStride ? view.byteStride : element;
    std::vector<T> values(a.count * std::size_t(n));
    for (std::size_t i = 0; i < a.count; ++i)
      for (int k = 0; k < n; ++k)
        values[i * std::size_t(n) + std::size_t(k)] =
            T(decode(base + i * stride + std::size_t(k) * c, a.componentType, a.normalized));
    if (a.sparse.isSparse) apply_sparse(a, element, n, what, &values);
    return values;
  }

 private:
  // Checks accessor `index` against `rule` and its buffer's bounds (before
  // anything is allocated from its count); returns its first element.
  const unsigned char* check(int index, const AccessorRule& rule, const std::string& where) const {
    const tinygltf::Accessor& a = accessor(index, where);
    const std::string what = where + ": " + rule.role + " accessor " + std::to_string(index);
    if (std::find(rule.types.begin(), rule.types.end(), a.type) == rule.types.end())
      throw InputError(path_, what + " has elements of type " + type_name(a.type) + ", which " + rule.role +
                                  " may not have");
    const std::vector<int>& allowed = a.normalized ? rule.normalized : rule.plain;
    const bool is_float = a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT;
    if (is_float ? !rule.floats || a.normalized
                 : std::find(allowed.begin(), allowed.end(), a.componentType) == allowed.end())
      throw InputError(path_, what + " holds " + (a.normalized ? "normalized " : "") +
                                  component_name(a.componentType) + " values, which " + rule.role + " may not hold");
    if (a.bufferView < 0)
      throw InputError(path_, what + " has no bufferView (zero-filled accessors are not read)");
    if (a.count > std::size_t(INT_MAX)) throw InputError(path_, what + " has more elements than scan2lod reads");

    const std::size_t element = std::size_t(component_size(a.componentType)) * std::size_t(type_components(a.type));
    const tinygltf::BufferView& view = buffer_view(a.bufferView, what);
    const std::size_t stride = view.byteStride ? view.byteStride : element;
    if (stride < element) throw InputError(path_, what + ": its bufferView's byteStride is shorter than an element");
    return bytes(a.bufferView, a.byteOffset, a.count, element, stride, what);
  }

  const tinygltf::Accessor& accessor(int index, const std::string& where) const {
    if (index < 0 || std::size_t(index) >= model_.accessors.size())
      throw InputError(path_, where + " names accessor " + std::to_string(index) + ", but the file has " +
                                  std::to_string(model_.accessors.size()));
    return model_.accessors[std::size_t(index)];
  }

  const tinygltf::BufferView& buffer_view(int index, const std::string& what) const {
    if (index < 0 || std::size_t(index) >= model_.bufferViews.size())
      throw InputError(path_, what + " names bufferView " + std::to_string(index) + ", but the file has " +
                                  std::to_string(model_.bufferViews.size()));
    return model_.bufferViews[std::size_t(index)];
  }

  // The first of `count` elements of `element` bytes, `stride` apart, from
  // `offset` into buffer view `view_index`; throws unless all lie inside it.
  const unsigned char* bytes(int view_index, std::size_t offset, std::size_t count, std::size_t element,
                             std::size_t stride, const std::string& what) const {
    const tinygltf::BufferView& view = buffer_view(view_index, what);
    if (view.buffer < 0 || std::size_t(view.buffer) >= model_.buffers.size())
      throw InputError(path_, what + ": bufferView " + std::to_string(view_index) +
                                  " names a buffer that does not exist");
    const std::vector<unsigned char>& data = model_.buffers[std::size_t(view.buffer)].data;
    if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
      throw InputError(path_, what + ": bufferView " + std::to_string(view_index) + " reaches past the end of its " +
                                  std::to_string(data.size()) + "-byte buffer");
    // Overflow-free form of offset + (count - 1) * stride + element <= length.
    const bool fits = count == 0 || (offset <= view.byteLength && element <= view.byteLength - offset &&
                                     (count - 1) <= (view.byteLength - offset - element) / stride);
    if (!fits)
      throw InputError(path_, what + ": " + std::to_string(count) + " elements reach past the end of bufferView " +
                                  std::to_string(view_index) + " (" + std::to_string(view.byteLength) + " bytes)");
    return data.data() + view.byteOffset + offset;
  }

  // glTF 2.0 §3.6.2.3: listed elements replace the dense ones.
  template <typename T>
  void apply_sparse(const tinygltf::Accessor& a, std::size_t element, int n, const std::string& what,
                    std::vector<T>* values) const {
    const int index_type = a.sparse.indices.componentType;
    if (index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
      throw InputError(path_, what + ": its sparse indices are " + component_name(index_type) +
                                  ", expected an unsigned integer type");
    if (a.sparse.count < 0 || std::size_t(a.sparse.count) > a.count)
      throw InputError(path_, what + " replaces " + std::to_string(a.sparse.count) + " of its " +
                                  std::to_string(a.count) + " elements");
    const std::size_t m = std::size_t(a.sparse.count);
    const std::size_t index_size = std::size_t(component_size(index_type));
    const std::size_t index_offset = std::size_t(std::max(0, a.sparse.indices.byteOffset));
    const std::size_t value_offset = std::size_t(std::max(0, a.sparse.values.byteOffset));
    const unsigned char* indices =
        bytes(a.sparse.indices.bufferView, index_offset, m, index_size, index_size, what + " (sparse indices)");
    const unsigned char* replacements =
        bytes(a.sparse.values.bufferView, value_offset, m, element, element, what + " (sparse values)");
    const std::size_t c = std::size_t(component_size(a.componentType));
    for (std::size_t j = 0; j < m; ++j) {
      const std::size_t i = std::size_t(decode(indices + j * index_size, index_type, false));
      if (i >= a.count)
        throw InputError(path_, what + ": sparse index " + std::to_string(i) + " is past its " +
                                    std::to_string(a.count) + " elements");
      for (int k = 0; k < n; ++k)
        (*values)[i * std::size_t(n) + std::size_t(k)] =
            T(decode(replacements + j * element + std::size_t(k) * c, a.componentType, a.normalized));
    }
  }

  const std::string& path_;
  const tinygltf::Model& model_;
};

const AccessorRule kPositionRule{
    "POSITION", {TINYGLTF_TYPE_VEC3}, true,
    {TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_SHORT,
     TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT},
    {TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_SHORT,
     TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT}};
const AccessorRule kNormalRule{
    "NORMAL", {TINYGLTF_TYPE_VEC3}, true, {TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_COMPONENT_TYPE_SHORT}, {}};
const AccessorRule kColorRule{
    "COLOR_0", {TINYGLTF_TYPE_VEC3, TINYGLTF_TYPE_VEC4}, true,
    {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT}, {}};
const AccessorRule kIndexRule{
    "indices", {TINYGLTF_TYPE_SCALAR}, false, {},
    {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
     TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT}};

// ---------------------------------------------------------------------------
// The scene: nodes with their world transforms, primitives as triangles.

Eigen::Affine3d local_transform(const tinygltf::Node& node) {
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  if (node.matrix.size() == 16) {
    for (int i = 0; i < 16; ++i) t.matrix()(i % 4, i / 4) = node.matrix[std::size_t(i)];  // column-major
    return t;
  }
  if (node.translation.size() == 3) t.translate(Vec3d(node.translation[0], node.translation[1], node.translation[2]));
  if (node.rotation.size() == 4)  // x, y, z, w
    t.rotate(Eigen::Quaterniond(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]).normalized());
  if (node.scale.size() == 3) t.scale(Vec3d(node.scale[0], node.scale[1], node.scale[2]));
  return t;
}

struct MeshInstance {
  int mesh;
  Eigen::Affine3d world;
};

// The default scene's nodes that draw a mesh, each with its world transform.
std::vector<MeshInstance> scene_meshes(const std::string& path, const tinygltf::Model& model) {
  const int node_count = int(model.nodes.size());
  std::vector<int> roots;
  const int scene = model.defaultScene >= 0 ? model.defaultScene : model.scenes.empty() ? -1 : 0;
  if (scene >= int(model.scenes.size()))
    throw InputError(path, "its default scene is " + std::to_string(scene) + ", but the file has " +
                               std::to_string(model.scenes.size()));
  if (scene >= 0) {
    roots = model.scenes[std::size_t(scene)].nodes;
  } else {  // no scene: every node that is no other node's child
    std::vector<char> is_child(std::size_t(node_count), 0);
    for (const tinygltf::Node& n : model.nodes)
      for (int c : n.children)
        if (c >= 0 && c < node_count) is_child[std::size_t(c)] = 1;
    for (int i = 0; i < node_count; ++i)
      if (!is_child[std::size_t(i)]) roots.push_back(i);
  }

  std::vector<MeshInstance> instances;
  std::vector<char> visited(std::size_t(node_count), 0);
  std::vector<std::pair<int, Eigen::Affine3d>> stack;
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.emplace_back(*it, Eigen::Affine3d::Identity());
  while (!stack.empty()) {
    const auto [index, parent] = stack.back();
    stack.pop_back();
    if (index < 0 || index >= node_count)
      throw InputError(path, "the scene names node " + std::to_string(index) + ", but the file has " +
                                 std::to_string(node_count));
    // A node reached twice would be drawn twice, or forever in a cycle.
    if (visited[std::size_t(index)])
      throw InputError(path, "node " + std::to_string(index) + " is reached twice: the node hierarchy must be a tree");
    visited[std::size_t(index)] = 1;
    const tinygltf::Node& node = model.nodes[std::size_t(index)];
    const Eigen::Affine3d world = parent * local_transform(node);
    if (node.mesh >= 0) {
      if (std::size_t(node.mesh) >= model.meshes.size())
        throw InputError(path, "node " + std::to_string(index) + " names mesh " + std::to_string(node.mesh) +
                                   ", but the file has " + std::to_string(model.meshes.size()));
      instances.push_back({node.mesh, world});
    }
    for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) stack.emplace_back(*it, world);
  }
  return instances;
}

// Primitives of one mesh instance that share their vertex accessors share
// their vertices, as the levels of a chain do.
struct VertexGroup {
  int position = -1, normal = -1, color = -1;
  std::vector<std::array<std::uint32_t, 3>> triangles;  // into the accessors' elements
};

int attribute(const tinygltf::Primitive& p, const char* name) {
  const auto it = p.attributes.find(name);
  return it == p.attributes.end() ? -1 : it->second;
}

// Appends the triangles `primitive` draws (glTF 2.0 §3.7.2.1) to `group`.
void add_triangles(const std::string& path, const AccessorReader& accessors, const tinygltf::Primitive& primitive,
                   const std::string& where, VertexGroup* group) {
  const std::size_t vertex_count = accessors.count(group->position, kPositionRule, where);
  for (const auto& [other, rule] : {std::pair{group->normal, &kNormalRule}, std::pair{group->color, &kColorRule}}) {
    const std::size_t count = other >= 0 ? accessors.count(other, *rule, where) : vertex_count;
    if (count != vertex_count)
      throw InputError(path, where + ": its " + rule->role + " has " + std::to_string(count) + " elements for " +
                                 std::to_string(vertex_count) + " positions");
  }
  std::vector<std::uint32_t> indices;
  if (primitive.indices >= 0) {
    int components = 0;
    indices = accessors.read<std::uint32_t>(primitive.indices, kIndexRule, where, &components);
    for (std::size_t i = 0; i < indices.size(); ++i)
      if (indices[i] >= vertex_count)
        throw InputError(path, where + ": index " + std::to_string(i) + " names vertex " +
                                   std::to_string(indices[i]) + ", but POSITION has " + std::to_string(vertex_count));
  } else {
    indices.resize(vertex_count);
    for (std::size_t i = 0; i < vertex_count; ++i) indices[i] = std::uint32_t(i);
  }
  const std::size_t n = indices.size();
  auto& out = group->triangles;
  switch (primitive.mode) {
    case TINYGLTF_MODE_TRIANGLES:
      if (n % 3 != 0)
        throw InputError(path, where + ": " + std::to_string(n) + " vertices do not make whole triangles");
      for (std::size_t i = 0; i < n; i += 3) out.push_back({indices[i], indices[i + 1], indices[i + 2]});
      break;
    case TINYGLTF_MODE_TRIANGLE_STRIP:  // every other triangle is wound the other way
      for (std::size_t i = 0; i + 2 < n; ++i)
        out.push_back({indices[i], indices[i + 1 + i % 2], indices[i + 2 - i % 2]});
      break;
    case TINYGLTF_MODE_TRIANGLE_FAN:
      for (std::size_t i = 0; i + 2 < n; ++i) out.push_back({indices[i + 1], indices[i + 2], indices[0]});
      break;
  }
}

// Appends the group's used vertices, in the world frame, and its triangles;
// with `exact`, the positions in double there too.
void append_group(const std::string& path, const AccessorReader& accessors, const VertexGroup& group,
                  const Eigen::Affine3d& world, const std::string& where, TriangleMesh* mesh, bool* all_normals,
                  bool* all_colors, std::vector<Vec3d>* exact) {
  int components = 0;
  const std::vector<float> positions = accessors.read<float>(group.position, kPositionRule, where, &components);
  std::vector<float> normals, colors;
  int color_components = 0;
  if (group.normal >= 0) normals = accessors.read<float>(group.normal, kNormalRule, where, &components);
  if (group.color >= 0) colors = accessors.read<float>(group.color, kColorRule, where, &color_components);
  *all_normals &= group.normal >= 0;
  *all_colors &= group.color >= 0;

  // Only the vertices a triangle uses, in the file's order.
  const std::size_t count = positions.size() / 3;
  std::vector<std::int64_t> remap(count, -1);
  for (const auto& t : group.triangles)
    for (std::uint32_t v : t) remap[v] = 0;
  const std::size_t first = mesh->positions.size();
  std::size_t next = first;
  for (std::int64_t& r : remap)
    if (r == 0) r = std::int64_t(next++);
  if (next > std::size_t(INT32_MAX)) throw InputError(path, where + ": more vertices than scan2lod reads");

  const Eigen::Matrix3d normal_matrix = world.linear().inverse().transpose();
  mesh->positions.resize(next);
  if (exact) exact->resize(next);
  mesh->normals.resize(next, Vec3f::Zero());
  mesh->colors.resize(next, Rgb{0, 0, 0});
  for (std::size_t v = 0; v < count; ++v) {
    if (remap[v] < 0) continue;
    const std::size_t out = std::size_t(remap[v]);
    const Vec3d p = world * Vec3d(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]);
    mesh->positions[out] = p.cast<float>();
    if (exact) (*exact)[out] = p;
    if (!normals.empty()) {
      const Vec3d n = normal_matrix * Vec3d(normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]);
      const double length = n.norm();
      if (length > 0 && std::isfinite(length)) mesh->normals[out] = (n / length).cast<float>();
    }
    if (!colors.empty())
      for (int k = 0; k < 3; ++k) {
        const double c = colors[v * std::size_t(color_components) + std::size_t(k)];
        mesh->colors[out][std::size_t(k)] = std::uint8_t(std::lround(std::clamp(c, 0.0, 1.0) * 255));
      }
  }
  // A mirroring transform turns counter-clockwise into clockwise.
  const bool mirrored = world.linear().determinant() < 0;
  for (const auto& t : group.triangles) {
    Triangle tri{std::int32_t(remap[t[0]]), std::int32_t(remap[t[1]]), std::int32_t(remap[t[2]])};
    if (mirrored) std::swap(tri[1], tri[2]);
    mesh->triangles.push_back(tri);
  }
}

bool is_triangle_mode(int mode) {
  return mode == TINYGLTF_MODE_TRIANGLES || mode == TINYGLTF_MODE_TRIANGLE_STRIP || mode == TINYGLTF_MODE_TRIANGLE_FAN;
}

// The scene's mesh; with `exact`, its positions in double as well.
TriangleMesh read_scene(const std::string& path, std::vector<Vec3d>* exact) {
  const tinygltf::Model model = load_model(path);
  check_required_extensions(path, model);
  const AccessorReader accessors(path, model);
  TriangleMesh mesh;
  bool all_normals = true, all_colors = true;
  std::size_t skipped = 0;
  for (const MeshInstance& instance : scene_meshes(path, model)) {
    const tinygltf::Mesh& m = model.meshes[std::size_t(instance.mesh)];
    const std::string mesh_name =
        "mesh " + std::to_string(instance.mesh) + (m.name.empty() ? "" : " ('" + m.name + "')");
    std::vector<VertexGroup> groups;
    std::map<std::tuple<int, int, int>, std::size_t> group_of;
    for (std::size_t p = 0; p < m.primitives.size(); ++p) {
      const tinygltf::Primitive& primitive = m.primitives[p];
      if (!is_triangle_mode(primitive.mode)) {
        ++skipped;
        continue;
      }
      const std::string where = mesh_name + " primitive " + std::to_string(p);
      VertexGroup key;
      key.position = attribute(primitive, "POSITION");
      key.normal = attribute(primitive, "NORMAL");
      key.color = attribute(primitive, "COLOR_0");
      if (key.position < 0) throw InputError(path, where + " has no POSITION attribute");
      const auto [it, added] = group_of.try_emplace({key.position, key.normal, key.color}, groups.size());
      if (added) groups.push_back(key);
      add_triangles(path, accessors, primitive, where, &groups[it->second]);
    }
    for (const VertexGroup& group : groups)
      append_group(path, accessors, group, instance.world, mesh_name, &mesh, &all_normals, &all_colors, exact);
  }
  if (mesh.triangles.empty())
    throw InputError(path, skipped ? "has no triangles: its scene draws only points or lines"
                                   : "has no triangles: its scene holds no mesh");
  if (!all_normals) mesh.normals.clear();
  if (!all_colors) mesh.colors.clear();
  return mesh;
}

}  // namespace

TriangleMesh read_gltf(const std::string& path) { return read_scene(path, nullptr); }

TriangleMesh read_gltf(const std::string& path, Vec3d* origin) {
  std::vector<Vec3d> exact;
  TriangleMesh mesh = read_scene(path, &exact);
  *origin = local_origin(exact);
  if (*origin != Vec3d::Zero()) mesh.positions = positions_about(exact, *origin);
  return mesh;
}

}  // namespace scan2lod
