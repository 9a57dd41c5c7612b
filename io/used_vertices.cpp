#include <scan2lod/io/used_vertices.h>

namespace scan2lod {

std::optional<UsedVertices> drop_unused_vertices(const TriangleMesh& mesh,
                                                 const std::vector<const std::vector<Triangle>*>& lists) {
  const std::size_t n = mesh.positions.size();
  std::vector<std::int32_t> remap(n, -1);  // 0 once used, then the new index
  std::size_t used = 0;
  for (const std::vector<Triangle>* list : lists)
    for (const Triangle& t : *list)
      for (std::int32_t i : t)
        if (remap[std::size_t(i)] < 0) remap[std::size_t(i)] = 0, ++used;
  if (used == n) return std::nullopt;

  UsedVertices out;
  TriangleMesh& v = out.vertices;
  v.positions.reserve(used);
  if (!mesh.normals.empty()) v.normals.reserve(used);
  if (!mesh.colors.empty()) v.colors.reserve(used);
  for (std::size_t i = 0; i < n; ++i) {
    if (remap[i] < 0) continue;
    remap[i] = std::int32_t(v.positions.size());
    v.positions.push_back(mesh.positions[i]);
    if (!mesh.normals.empty()) v.normals.push_back(mesh.normals[i]);
    if (!mesh.colors.empty()) v.colors.push_back(mesh.colors[i]);
  }
  out.lists.reserve(lists.size());
  for (const std::vector<Triangle>* list : lists) {
    std::vector<Triangle>& renumbered = out.lists.emplace_back(*list);
    for (Triangle& t : renumbered)
      for (std::int32_t& i : t) i = remap[std::size_t(i)];
  }
  return out;
}

}  // namespace scan2lod
