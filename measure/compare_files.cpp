#include <scan2lod/measure/compare_files.h>

#include <scan2lod/core/error.h>
#include <scan2lod/io/mesh_file.h>

namespace scan2lod {

MeshPair read_in_one_frame(const std::string& a, const std::string& b) {
  MeshPair pair;
  Vec3d origin_a, origin_b;
  pair.a = read_mesh(a, &origin_a);
  pair.b = read_mesh(b, &origin_b);
  if (origin_a != origin_b)
    for (Vec3f& p : pair.b.positions) p = ((origin_b - origin_a) + p.cast<double>()).cast<float>();
  return pair;
}

SurfaceComparison compare_named(const TriangleMesh& a, const TriangleMesh& b, const CompareOptions& options,
                                const std::string& name_a, const std::string& name_b) {
  try {
    return compare_surfaces(a, b, options);
  } catch (const InputError& e) {
    throw InputError(name_a + " vs " + name_b, e.what());
  }
}

}  // namespace scan2lod
