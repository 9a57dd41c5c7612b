#include <scan2lod/delivery/cluster_geometry.h>

#include <scan2lod/lod/clusters/paged_model.h>

#include <cassert>

namespace scan2lod {

ClusterGeometry::ClusterGeometry(const LodModel& model) : model_(model), pages_(model.clusters->paged.get()) {
  assert(!model.clusters->spool);
}

ClusterTriangles ClusterGeometry::triangles(std::int32_t c) {
  const ClusterHierarchy& h = *model_.clusters;
  const Cluster& cl = h.clusters[std::size_t(c)];
  ClusterTriangles out;
  out.count = cl.triangle_count;
  if (!pages_) {
    const VertexArray& v = model_.vertices;
    out.triangles = h.triangles.data() + cl.first_triangle;
    out.positions = v.positions.data();
    if (!v.normals.empty()) out.normals = v.normals.data();
    if (!v.colors.empty()) out.colors = v.colors.data();
    return out;
  }
  const std::size_t p = pages_->page_of(c);
  const PageGeometry& g = pages_->page(p);
  out.triangles = g.triangles.data() + (cl.first_triangle - pages_->first_triangle(p));
  out.positions = g.positions.data();
  if (!g.normals.empty()) out.normals = g.normals.data();
  if (!g.colors.empty()) out.colors = g.colors.data();
  out.model_vertices = g.model_vertices.data();
  return out;
}

}  // namespace scan2lod
