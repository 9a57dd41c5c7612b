#include <scan2lod/measure/topology.h>

#include <scan2lod/core/error.h>
#include <scan2lod/core/mesh_edges.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <string>

namespace scan2lod {
namespace {

// Union-find over vertex indices with path halving; union by index keeps it
// deterministic, and path halving alone is fast enough for mesh-sized forests.
class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), 0u);
  }
  std::uint32_t find(std::uint32_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a < b) parent_[b] = a;
    else if (b < a) parent_[a] = b;
  }

 private:
  std::vector<std::uint32_t> parent_;
};

bool collapsed(const Triangle& t) { return t[0] == t[1] || t[1] == t[2] || t[0] == t[2]; }

}  // namespace

void check_triangle_indices(const TriangleMesh& mesh) {
  const auto n = std::int64_t(mesh.positions.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (std::int32_t v : mesh.triangles[t])
      if (v < 0 || v >= n)
        throw InputError("", "triangle " + std::to_string(t) + " references vertex " +
                                 std::to_string(v) + " but the mesh has " + std::to_string(n) +
                                 " vertices");
}

bool triangle_is_degenerate(const TriangleMesh& mesh, std::size_t t) {
  const Triangle& tri = mesh.triangles[t];
  if (collapsed(tri)) return true;
  // Float, like the Embree kernels that choke on these triangles.
  const Vec3f& a = mesh.positions[tri[0]];
  Vec3f n = (mesh.positions[tri[1]] - a).cross(mesh.positions[tri[2]] - a);
  return n.x() == 0.f && n.y() == 0.f && n.z() == 0.f;
}

namespace {

// triangle_components without the index check, for callers that made it.
std::vector<int> label_components(const TriangleMesh& mesh, int* count) {
  DisjointSets sets(mesh.positions.size());
  for (const Triangle& t : mesh.triangles) {
    if (collapsed(t)) continue;
    sets.unite(t[0], t[1]);
    sets.unite(t[0], t[2]);
  }
  std::vector<int> root_id(mesh.positions.size(), -1);
  std::vector<int> ids(mesh.triangles.size(), -1);
  int n = 0;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const Triangle& t = mesh.triangles[i];
    if (collapsed(t)) continue;
    int& id = root_id[sets.find(t[0])];
    if (id < 0) id = n++;
    ids[i] = id;
  }
  if (count) *count = n;
  return ids;
}

}  // namespace

std::vector<int> triangle_components(const TriangleMesh& mesh, int* count) {
  check_triangle_indices(mesh);
  return label_components(mesh, count);
}

MeshTopology mesh_topology(const TriangleMesh& mesh) {
  check_triangle_indices(mesh);
  MeshTopology topo;
  topo.vertices = mesh.positions.size();
  topo.triangles = mesh.triangles.size();

  std::vector<char> referenced(mesh.positions.size(), 0);
  std::vector<Triangle> surface;  // without collapsed triangles, which bound nothing
  surface.reserve(mesh.triangles.size());
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    if (triangle_is_degenerate(mesh, i)) ++topo.degenerate_triangles;
    const Triangle& t = mesh.triangles[i];
    if (collapsed(t)) continue;
    surface.push_back(t);
    for (std::int32_t v : t) referenced[v] = 1;
  }
  topo.referenced_vertices = std::size_t(std::count(referenced.begin(), referenced.end(), 1));

  const MeshEdges edges = mesh_edges(surface, mesh.positions.size());
  topo.edges = edges.size();
  DisjointSets boundary(mesh.positions.size());
  std::vector<char> on_boundary(mesh.positions.size(), 0);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    if (edges.uses[e] == 1) {
      ++topo.boundary_edges;
      const auto a = std::uint32_t(edges.ends[e][0]), b = std::uint32_t(edges.ends[e][1]);
      boundary.unite(a, b);
      on_boundary[a] = on_boundary[b] = 1;
    } else if (edges.uses[e] > 2) {
      ++topo.non_manifold_edges;
    }
  }
  for (std::size_t v = 0; v < on_boundary.size(); ++v)
    if (on_boundary[v] && boundary.find(std::uint32_t(v)) == v) ++topo.boundary_loops;

  int count = 0;
  std::vector<int> ids = label_components(mesh, &count);
  topo.components = std::size_t(count);
  std::vector<std::size_t> sizes(std::size_t(count), 0);
  for (int id : ids)
    if (id >= 0) ++sizes[std::size_t(id)];
  if (!sizes.empty()) topo.largest_component_triangles = *std::max_element(sizes.begin(), sizes.end());

  topo.euler_characteristic =
      long(topo.referenced_vertices) - long(topo.edges) + long(surface.size());
  return topo;
}

TriangleMesh drop_small_components(const TriangleMesh& mesh, double min_fraction) {
  int count = 0;
  std::vector<int> ids = triangle_components(mesh, &count);
  std::vector<std::size_t> sizes(std::size_t(count), 0);
  for (int id : ids)
    if (id >= 0) ++sizes[std::size_t(id)];
  const double min_size = min_fraction * double(mesh.triangles.size());

  TriangleMesh out;
  std::vector<std::int32_t> remap(mesh.positions.size(), -1);
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    if (ids[i] < 0 || double(sizes[std::size_t(ids[i])]) < min_size) continue;
    Triangle t = mesh.triangles[i];
    for (std::int32_t& v : t) {
      if (remap[v] < 0) {
        remap[v] = std::int32_t(out.positions.size());
        out.positions.push_back(mesh.positions[v]);
        if (!mesh.normals.empty()) out.normals.push_back(mesh.normals[v]);
        if (!mesh.colors.empty()) out.colors.push_back(mesh.colors[v]);
      }
      v = remap[v];
    }
    out.triangles.push_back(t);
  }
  return out;
}

}  // namespace scan2lod
