#include "core/compact_mesh.h"

namespace scan2lod {

TriangleMesh compact_mesh(const std::vector<Vec3f>& positions, const std::vector<Vec3f>& normals,
                          const std::vector<Rgb>& colors, const std::vector<std::vector<Triangle>*>& lists) {
  std::vector<std::int32_t> remap(positions.size(), -1);
  TriangleMesh out;
  for (std::vector<Triangle>* list : lists)
    for (Triangle& t : *list)
      for (std::int32_t& i : t) {
        std::int32_t& r = remap[std::size_t(i)];
        if (r < 0) {
          r = std::int32_t(out.positions.size());
          out.positions.push_back(positions[std::size_t(i)]);
          if (!normals.empty()) out.normals.push_back(normals[std::size_t(i)]);
          if (!colors.empty()) out.colors.push_back(colors[std::size_t(i)]);
        }
        i = r;
      }
  return out;
}

}  // namespace scan2lod
