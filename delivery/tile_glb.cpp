#include <scan2lod/delivery/tile_glb.h>

#include <meshoptimizer.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstring>
#include <unordered_map>

namespace scan2lod {
namespace {

using json = nlohmann::json;

constexpr int kFloat = 5126, kShort = 5122, kUnsignedByte = 5121, kUnsignedShort = 5123, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

// glTF's y-up frame from the model's z-up one (3D Tiles turns it back).
Vec3f to_gltf(const Vec3f& p) { return Vec3f(p.x(), p.z(), -p.y()); }

Vec3f unit_or_up(const Vec3f& n) {
  const float length = n.norm();
  return length > 1e-12f && std::isfinite(length) ? Vec3f(n / length) : Vec3f(0, 0, 1);
}

// The tile's own vertices and triangles, in the order the codecs like.
struct LocalMesh {
  std::vector<std::int32_t> source;  // local vertex -> model vertex
  std::vector<unsigned> indices;
};

LocalMesh local_mesh(const std::vector<Triangle>& triangles) {
  LocalMesh m;
  std::unordered_map<std::int32_t, unsigned> local;
  local.reserve(triangles.size());
  m.indices.reserve(triangles.size() * 3);
  for (const Triangle& t : triangles)
    for (std::int32_t v : t) {
      auto [it, added] = local.emplace(v, unsigned(m.source.size()));
      if (added) m.source.push_back(v);
      m.indices.push_back(it->second);
    }
  const std::size_t n = m.source.size();
  meshopt_optimizeVertexCache(m.indices.data(), m.indices.data(), m.indices.size(), n);
  std::vector<unsigned> remap(n);
  meshopt_optimizeVertexFetchRemap(remap.data(), m.indices.data(), m.indices.size(), n);
  meshopt_remapIndexBuffer(m.indices.data(), m.indices.data(), m.indices.size(), remap.data());
  std::vector<std::int32_t> source(n);
  for (std::size_t i = 0; i < n; ++i) source[remap[i]] = m.source[i];
  m.source = std::move(source);
  return m;
}

// One buffer view's bytes before compression, and how glTF reads them.
struct Stream {
  std::vector<unsigned char> bytes;
  std::size_t stride = 0, count = 0;
  int target = kArrayBuffer;
  bool indices = false;
};

template <class T>
void append(std::vector<unsigned char>* bytes, const T& value) {
  const auto* p = reinterpret_cast<const unsigned char*>(&value);
  bytes->insert(bytes->end(), p, p + sizeof value);
}

void pad4(std::vector<unsigned char>* bytes, unsigned char with = 0) {
  while (bytes->size() % 4) bytes->push_back(with);
}

struct Accessors {
  json list = json::array();
  int position = -1, normal = -1, color = -1, indices = -1;
};

Stream position_stream(const VertexArray& v, const LocalMesh& m, const PositionGrid& grid, bool quantize,
                       json* min, json* max) {
  Stream s;
  s.count = m.source.size();
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  const Vec3f centre = to_gltf(grid.centre);
  for (std::int32_t i : m.source) {
    const Vec3f p = to_gltf(v.positions[std::size_t(i)]);
    for (int k = 0; k < 3; ++k) {
      if (quantize) {
        const int q = std::clamp(int(std::lround((p[k] - centre[k]) / grid.scale * 32767.f)), -32767, 32767);
        append(&s.bytes, std::int16_t(q));
        lo[std::size_t(k)] = std::min(lo[std::size_t(k)], double(q));
        hi[std::size_t(k)] = std::max(hi[std::size_t(k)], double(q));
      } else {
        append(&s.bytes, p[k]);
        lo[std::size_t(k)] = std::min(lo[std::size_t(k)], double(p[k]));
        hi[std::size_t(k)] = std::max(hi[std::size_t(k)], double(p[k]));
      }
    }
    if (quantize) append(&s.bytes, std::int16_t(0));
  }
  s.stride = quantize ? 8 : 12;
  *min = lo;
  *max = hi;
  return s;
}

Stream normal_stream(const VertexArray& v, const LocalMesh& m, bool quantize) {
  Stream s;
  s.count = m.source.size();
  for (std::int32_t i : m.source) {
    const Vec3f n = unit_or_up(to_gltf(v.normals[std::size_t(i)]));
    if (quantize) {
      // 16 bits, not 8: 8-bit normals are off unit length by up to 1 %,
      // which validators flag (as io/gltf_file.cpp writes them).
      for (int k = 0; k < 3; ++k) append(&s.bytes, std::int16_t(std::lround(n[k] * 32767.f)));
      append(&s.bytes, std::int16_t(0));
    } else {
      for (int k = 0; k < 3; ++k) append(&s.bytes, n[k]);
    }
  }
  s.stride = quantize ? 8 : 12;
  return s;
}

Stream color_stream(const VertexArray& v, const LocalMesh& m) {
  Stream s;
  s.count = m.source.size();
  for (std::int32_t i : m.source) {
    const Rgb& c = v.colors[std::size_t(i)];
    s.bytes.insert(s.bytes.end(), {c[0], c[1], c[2], 255});
  }
  s.stride = 4;
  return s;
}

Stream index_stream(const LocalMesh& m) {
  Stream s;
  s.count = m.indices.size();
  s.target = kElementArrayBuffer;
  s.indices = true;
  // 65535 is the primitive-restart value of 16-bit indices: not a vertex.
  const bool narrow = m.source.size() <= 65535;
  for (unsigned i : m.indices) {
    if (narrow) append(&s.bytes, std::uint16_t(i));
    else append(&s.bytes, std::uint32_t(i));
  }
  s.stride = narrow ? 2 : 4;
  return s;
}

// meshoptimizer's encoding of a stream (EXT_meshopt_compression: ATTRIBUTES
// or TRIANGLES mode).
std::vector<unsigned char> encoded(const Stream& s) {
  std::vector<unsigned char> out;
  if (s.indices) {
    std::vector<unsigned> indices(s.count);
    for (std::size_t i = 0; i < s.count; ++i) {
      if (s.stride == 2) {
        std::uint16_t v;
        std::memcpy(&v, s.bytes.data() + i * 2, 2);
        indices[i] = v;
      } else {
        std::memcpy(&indices[i], s.bytes.data() + i * 4, 4);
      }
    }
    std::size_t vertices = 0;
    for (unsigned i : indices) vertices = std::max<std::size_t>(vertices, i + 1);
    out.resize(meshopt_encodeIndexBufferBound(s.count, vertices));
    out.resize(meshopt_encodeIndexBuffer(out.data(), out.size(), indices.data(), s.count));
  } else {
    out.resize(meshopt_encodeVertexBufferBound(s.count, s.stride));
    out.resize(meshopt_encodeVertexBuffer(out.data(), out.size(), s.bytes.data(), s.count, s.stride));
  }
  return out;
}

// The JSON chunk and the binary chunk in the GLB container (glTF 2.0, §4.4).
std::vector<unsigned char> glb_container(const json& document, std::vector<unsigned char> bin) {
  std::string text = document.dump();
  while (text.size() % 4) text.push_back(' ');
  pad4(&bin);
  std::vector<unsigned char> out;
  const std::uint32_t total = std::uint32_t(12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin.size()));
  append(&out, std::uint32_t(0x46546C67));  // "glTF"
  append(&out, std::uint32_t(2));
  append(&out, total);
  append(&out, std::uint32_t(text.size()));
  append(&out, std::uint32_t(0x4E4F534A));  // "JSON"
  out.insert(out.end(), text.begin(), text.end());
  if (!bin.empty()) {
    append(&out, std::uint32_t(bin.size()));
    append(&out, std::uint32_t(0x004E4942));  // "BIN\0"
    out.insert(out.end(), bin.begin(), bin.end());
  }
  return out;
}

// Lays the streams out as buffer views: in the binary chunk as they are, or
// compressed there with the uncompressed layout in a fallback buffer that
// holds no bytes (EXT_meshopt_compression, "fallback": true).
json buffer_views(const std::vector<Stream>& streams, bool meshopt, std::vector<unsigned char>* bin,
                  json* buffers) {
  json views = json::array();
  std::size_t fallback_length = 0;
  for (const Stream& s : streams) {
    json view = {{"byteLength", s.bytes.size()}, {"target", s.target}};
    if (!s.indices) view["byteStride"] = s.stride;
    if (meshopt) {
      const std::vector<unsigned char> packed = encoded(s);
      pad4(bin);
      view["buffer"] = 1;
      view["byteOffset"] = fallback_length;
      view["extensions"]["EXT_meshopt_compression"] = {{"buffer", 0},
                                                      {"byteOffset", bin->size()},
                                                      {"byteLength", packed.size()},
                                                      {"byteStride", s.stride},
                                                      {"count", s.count},
                                                      {"mode", s.indices ? "TRIANGLES" : "ATTRIBUTES"}};
      bin->insert(bin->end(), packed.begin(), packed.end());
      fallback_length += (s.bytes.size() + 3) & ~std::size_t(3);
    } else {
      pad4(bin);
      view["buffer"] = 0;
      view["byteOffset"] = bin->size();
      bin->insert(bin->end(), s.bytes.begin(), s.bytes.end());
    }
    views.push_back(view);
  }
  pad4(bin);
  *buffers = json::array({{{"byteLength", bin->size()}}});
  if (meshopt)
    buffers->push_back({{"byteLength", fallback_length},
                        {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}});
  return views;
}

}  // namespace

TileGlb tile_glb(const VertexArray& vertices, const std::vector<Triangle>& triangles, const PositionGrid& grid,
                 const TileGlbOptions& options) {
  assert(!triangles.empty());
  const LocalMesh m = local_mesh(triangles);
  json min, max;
  std::vector<Stream> streams;
  streams.push_back(position_stream(vertices, m, grid, options.quantize, &min, &max));
  const bool normals = !vertices.normals.empty(), colors = !vertices.colors.empty();
  if (normals) streams.push_back(normal_stream(vertices, m, options.quantize));
  if (colors) streams.push_back(color_stream(vertices, m));
  streams.push_back(index_stream(m));

  json doc;
  doc["asset"] = {{"version", "2.0"}, {"generator", options.generator}};
  std::vector<unsigned char> bin;
  json buffers;
  doc["bufferViews"] = buffer_views(streams, options.meshopt, &bin, &buffers);
  doc["buffers"] = buffers;

  const int component = options.quantize ? kShort : kFloat;
  json accessors = json::array();
  int view = 0;
  json attributes;
  accessors.push_back({{"bufferView", view++}, {"componentType", component}, {"normalized", options.quantize},
                       {"count", m.source.size()}, {"type", "VEC3"}, {"min", min}, {"max", max}});
  attributes["POSITION"] = 0;
  if (normals) {
    attributes["NORMAL"] = int(accessors.size());
    accessors.push_back({{"bufferView", view++}, {"componentType", component}, {"normalized", options.quantize},
                         {"count", m.source.size()}, {"type", "VEC3"}});
  }
  if (colors) {
    attributes["COLOR_0"] = int(accessors.size());
    accessors.push_back({{"bufferView", view++}, {"componentType", kUnsignedByte}, {"normalized", true},
                         {"count", m.source.size()}, {"type", "VEC3"}});
  }
  const int index_accessor = int(accessors.size());
  accessors.push_back({{"bufferView", view++},
                       {"componentType", streams.back().stride == 2 ? kUnsignedShort : kUnsignedInt},
                       {"count", m.indices.size()},
                       {"type", "SCALAR"}});
  // The normalized flag is for integer attributes only.
  for (json& a : accessors)
    if (a.contains("normalized") && !a["normalized"].get<bool>()) a.erase("normalized");
  doc["accessors"] = accessors;
  doc["materials"] = json::array(
      {{{"name", "scan"}, {"pbrMetallicRoughness", {{"metallicFactor", 0}, {"roughnessFactor", 0.8}}}}});
  doc["meshes"] = json::array(
      {{{"primitives",
         json::array({{{"attributes", attributes}, {"indices", index_accessor}, {"material", 0}, {"mode", 4}}})}}});
  json node = {{"mesh", 0}};
  if (options.quantize) {
    const Vec3f t = to_gltf(grid.centre);
    node["translation"] = {t.x(), t.y(), t.z()};
    node["scale"] = {grid.scale, grid.scale, grid.scale};
  }
  doc["nodes"] = json::array({node});
  doc["scenes"] = json::array({{{"nodes", {0}}}});
  doc["scene"] = 0;
  std::vector<std::string> used;
  if (options.quantize) used.push_back("KHR_mesh_quantization");
  if (options.meshopt) used.push_back("EXT_meshopt_compression");
  if (!used.empty()) {
    doc["extensionsUsed"] = used;
    doc["extensionsRequired"] = used;
  }
  TileGlb out;
  out.bytes = glb_container(doc, std::move(bin));
  out.vertices = m.source.size();
  out.triangles = triangles.size();
  return out;
}

}  // namespace scan2lod
