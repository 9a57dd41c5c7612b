#include <scan2lod/lod/clusters/page_geometry.h>

#include <cstring>
#include <limits>

namespace scan2lod {
namespace {

constexpr std::uint32_t kNormals = 1, kColors = 2, kShortIndices = 4;
constexpr std::size_t kHead = 16;

std::size_t up4(std::size_t n) { return (n + 3) & ~std::size_t(3); }
std::size_t up8(std::size_t n) { return (n + 7) & ~std::size_t(7); }

struct Layout {
  std::size_t ids, positions, normals, colors, indices, end;
};

Layout layout_of(std::size_t v, std::size_t t, std::uint32_t flags) {
  Layout l;
  l.ids = kHead;
  l.positions = l.ids + 4 * v;
  l.normals = l.positions + 12 * v;
  l.colors = l.normals + ((flags & kNormals) ? 12 * v : 0);
  l.indices = up4(l.colors + ((flags & kColors) ? 3 * v : 0));
  l.end = up8(l.indices + t * 3 * ((flags & kShortIndices) ? 2 : 4));
  return l;
}

}  // namespace

std::size_t PageGeometry::bytes() const {
  return model_vertices.size() * 4 + (positions.size() + normals.size()) * sizeof(Vec3f) + colors.size() * 3 +
         triangles.size() * sizeof(Triangle);
}

bool PageEncoder::encode(const Triangle* triangles, std::size_t count, const VertexArray& vertices,
                         std::vector<std::uint8_t>* blob, Aabb* box) {
  local_.clear();
  model_vertices_.clear();
  blob->clear();
  for (std::size_t t = 0; t < count; ++t)
    for (const std::int32_t v : triangles[t])
      if (v < 0 || std::size_t(v) >= vertices.size()) return false;
  local_triangles_.resize(count);
  for (std::size_t t = 0; t < count; ++t)
    for (int k = 0; k < 3; ++k) {
      const std::int32_t v = triangles[t][k];
      const std::int32_t next = std::int32_t(model_vertices_.size());
      const std::int32_t local = local_.insert(std::uint64_t(std::uint32_t(v)), next);
      if (local == next) model_vertices_.push_back(std::uint32_t(v));
      local_triangles_[t][k] = local;
    }
  const std::size_t n = model_vertices_.size();
  const bool normals = !vertices.normals.empty(), colors = !vertices.colors.empty();
  const std::uint32_t flags = (normals ? kNormals : 0) | (colors ? kColors : 0) | (n <= 65536 ? kShortIndices : 0);
  const Layout l = layout_of(n, count, flags);
  blob->assign(l.end, 0);
  std::uint8_t* b = blob->data();
  const std::uint32_t head[4] = {std::uint32_t(n), std::uint32_t(count), flags, 0};
  std::memcpy(b, head, kHead);
  std::memcpy(b + l.ids, model_vertices_.data(), 4 * n);
  *box = Aabb();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3f& p = vertices.positions[model_vertices_[i]];
    box->extend(p);
    std::memcpy(b + l.positions + 12 * i, p.data(), 12);
    if (normals) std::memcpy(b + l.normals + 12 * i, vertices.normals[model_vertices_[i]].data(), 12);
    if (colors) std::memcpy(b + l.colors + 3 * i, vertices.colors[model_vertices_[i]].data(), 3);
  }
  if (flags & kShortIndices) {
    std::uint16_t* out = reinterpret_cast<std::uint16_t*>(b + l.indices);
    for (std::size_t t = 0; t < count; ++t)
      for (int k = 0; k < 3; ++k) out[3 * t + std::size_t(k)] = std::uint16_t(local_triangles_[t][k]);
  } else {
    std::memcpy(b + l.indices, local_triangles_.data(), 12 * count);
  }
  return true;
}

std::string decode_page(const std::uint8_t* blob, std::size_t bytes, std::size_t triangles, bool normals,
                        bool colors, std::uint64_t first_vertex, std::uint64_t vertex_count, PageGeometry* page) {
  if (bytes < kHead) return "holds " + std::to_string(bytes) + " bytes, less than its 16-byte head";
  std::uint32_t head[4];
  std::memcpy(head, blob, kHead);
  const std::size_t v = head[0], t = head[1];
  const std::uint32_t flags = head[2];
  if (t != triangles)
    return "holds " + std::to_string(t) + " triangles, its clusters " + std::to_string(triangles);
  if (bool(flags & kNormals) != normals || bool(flags & kColors) != colors || (flags & ~7u) || head[3] != 0)
    return "flags " + std::to_string(flags) + " disagree with the model's normals and colours";
  if (v > 3 * t || ((flags & kShortIndices) && v > 65536))
    return std::to_string(v) + " vertices for " + std::to_string(t) + " triangles";
  const Layout l = layout_of(v, t, flags);
  if (l.end != bytes)
    return "holds " + std::to_string(bytes) + " bytes, its counts need " + std::to_string(l.end);
  page->model_vertices.resize(v);
  std::memcpy(page->model_vertices.data(), blob + l.ids, 4 * v);
  for (const std::uint32_t m : page->model_vertices)
    if (m < first_vertex || m - first_vertex >= vertex_count)
      return "names model vertex " + std::to_string(m) + " outside " + std::to_string(first_vertex) + "+" +
             std::to_string(vertex_count);
  page->positions.resize(v);
  std::memcpy(static_cast<void*>(page->positions.data()), blob + l.positions, 12 * v);
  page->normals.resize(normals ? v : 0);
  if (normals) std::memcpy(static_cast<void*>(page->normals.data()), blob + l.normals, 12 * v);
  page->colors.resize(colors ? v : 0);
  if (colors) std::memcpy(page->colors.data(), blob + l.colors, 3 * v);
  page->triangles.resize(t);
  if (flags & kShortIndices) {
    const std::uint8_t* in = blob + l.indices;
    for (std::size_t i = 0; i < t; ++i)
      for (int k = 0; k < 3; ++k) {
        std::uint16_t x;
        std::memcpy(&x, in + 2 * (3 * i + std::size_t(k)), 2);
        page->triangles[i][k] = x;
      }
  } else {
    std::memcpy(page->triangles.data(), blob + l.indices, 12 * t);
  }
  for (std::size_t i = 0; i < t; ++i)
    for (int k = 0; k < 3; ++k)
      if (std::uint32_t(page->triangles[i][k]) >= v)
        return "triangle " + std::to_string(i) + " names local vertex " + std::to_string(page->triangles[i][k]) +
               " of " + std::to_string(v);
  return "";
}

}  // namespace scan2lod
