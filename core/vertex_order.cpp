#include <scan2lod/core/vertex_order.h>

#include <scan2lod/core/morton.h>
#include <scan2lod/core/sort_on_cores.h>

#include <algorithm>
#include <cstdint>
#include <thread>
#include <vector>

namespace scan2lod {

namespace {

template <class T>
void gather(std::vector<T>* values, const std::vector<std::int32_t>& old_of_new) {
  if (values->empty()) return;
  std::vector<T> out(old_of_new.size());
  for (std::size_t i = 0; i < old_of_new.size(); ++i) out[i] = (*values)[std::size_t(old_of_new[i])];
  values->swap(out);
}

bool before(const Vec3f& a, const Vec3f& b) {
  for (int i = 0; i < 3; ++i)
    if (a[i] != b[i]) return a[i] < b[i];
  return false;
}

}  // namespace

void order_vertices(TriangleMesh* mesh) {
  const std::size_t n = mesh->positions.size();
  std::vector<std::uint8_t> used(n, 0);
  for (const Triangle& t : mesh->triangles)
    for (std::int32_t v : t) used[std::size_t(v)] = 1;
  Aabb box;
  for (std::size_t v = 0; v < n; ++v)
    if (used[v]) box.extend(mesh->positions[v]);
  const Vec3f scale = (box.max - box.min).cwiseMax(Vec3f::Constant(1e-30f)).cwiseInverse() * float((1 << 21) - 1);
  struct Key {
    std::uint64_t code;
    std::int32_t vertex;
  };
  std::vector<Key> keys;
  keys.reserve(n);
  for (std::size_t v = 0; v < n; ++v) {
    if (!used[v]) continue;
    const Vec3f q = ((mesh->positions[v] - box.min).cwiseProduct(scale)).cwiseMax(Vec3f::Zero());
    keys.push_back({morton_code(std::uint64_t(q.x()), std::uint64_t(q.y()), std::uint64_t(q.z())), std::int32_t(v)});
  }
  used = {};
  const bool normals = !mesh->normals.empty(), colors = !mesh->colors.empty();
  // A total order on the values (the number last, for vertices equal in
  // all of them): the same on any core count.
  sort_on_cores(keys.begin(), keys.end(), int(std::thread::hardware_concurrency()), [&](const Key& a, const Key& b) {
    if (a.code != b.code) return a.code < b.code;
    const std::size_t u = std::size_t(a.vertex), w = std::size_t(b.vertex);
    if (mesh->positions[u] != mesh->positions[w]) return before(mesh->positions[u], mesh->positions[w]);
    if (normals && mesh->normals[u] != mesh->normals[w]) return before(mesh->normals[u], mesh->normals[w]);
    if (colors && mesh->colors[u] != mesh->colors[w]) return mesh->colors[u] < mesh->colors[w];
    return a.vertex < b.vertex;
  });
  std::vector<std::int32_t> old_of_new(keys.size()), new_of_old(n, -1);
  for (std::size_t i = 0; i < keys.size(); ++i) {
    old_of_new[i] = keys[i].vertex;
    new_of_old[std::size_t(keys[i].vertex)] = std::int32_t(i);
  }
  keys = {};
  for (Triangle& t : mesh->triangles)
    for (std::int32_t& v : t) v = new_of_old[std::size_t(v)];
  new_of_old = {};
  gather(&mesh->positions, old_of_new);
  gather(&mesh->normals, old_of_new);
  gather(&mesh->colors, old_of_new);
}

}  // namespace scan2lod
