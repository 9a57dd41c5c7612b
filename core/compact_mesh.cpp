#include <scan2lod/core/compact_mesh.h>

namespace scan2lod {

TriangleMesh compact_mesh(ArrayView<Vec3f> positions, ArrayView<Vec3f> normals,
                          ArrayView<Rgb> colors, const std::vector<std::vector<Triangle>*>& lists) {
  // Number the used vertices first, so that each output array is allocated
  // once at its final size (growing them would copy and fault in pages).
  std::vector<std::int32_t> remap(positions.size(), -1);
  std::int32_t used = 0;
  for (std::vector<Triangle>* list : lists)
    for (Triangle& t : *list)
      for (std::int32_t& i : t) {
        std::int32_t& r = remap[std::size_t(i)];
        if (r < 0) r = used++;
        i = r;
      }
  TriangleMesh out;
  out.positions.resize(std::size_t(used));
  if (!normals.empty()) out.normals.resize(std::size_t(used));
  if (!colors.empty()) out.colors.resize(std::size_t(used));
  for (std::size_t v = 0; v < remap.size(); ++v) {
    const std::int32_t r = remap[v];
    if (r < 0) continue;
    out.positions[std::size_t(r)] = positions[v];
    if (!normals.empty()) out.normals[std::size_t(r)] = normals[v];
    if (!colors.empty()) out.colors[std::size_t(r)] = colors[v];
  }
  return out;
}

// compact_mesh numbers into a fresh table and then scans it whole, which is
// sequential and best for a large level; this touches only the entries the
// triangles use, so that a caller compacting thousands of small levels over
// one vertex array (one table, reset through `used`) pays for those alone.
void renumber_used(std::vector<Triangle>* triangles, std::vector<std::int32_t>* remap,
                   std::vector<std::int32_t>* used) {
  for (Triangle& t : *triangles)
    for (std::int32_t& i : t) {
      std::int32_t& r = (*remap)[std::size_t(i)];
      if (r < 0) {
        r = std::int32_t(used->size());
        used->push_back(i);
      }
      i = r;
    }
}

}  // namespace scan2lod
