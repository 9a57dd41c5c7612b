#include <scan2lod/measure/comparison_json.h>

namespace scan2lod {

nlohmann::json distance_stats_json(const DistanceStats& s) {
  return {{"mean", s.mean}, {"rms", s.rms}, {"p95", s.p95}, {"max", s.max}, {"samples", s.samples}};
}

nlohmann::json topology_json(const MeshTopology& t) {
  return {{"vertices", t.vertices},
          {"triangles", t.triangles},
          {"referenced_vertices", t.referenced_vertices},
          {"edges", t.edges},
          {"boundary_edges", t.boundary_edges},
          {"boundary_loops", t.boundary_loops},
          {"non_manifold_edges", t.non_manifold_edges},
          {"components", t.components},
          {"largest_component_triangles", t.largest_component_triangles},
          {"degenerate_triangles", t.degenerate_triangles},
          {"euler_characteristic", t.euler_characteristic}};
}

nlohmann::json comparison_json(const SurfaceComparison& c) {
  return {{"a_to_b", distance_stats_json(c.a_to_b)},
          {"b_to_a", distance_stats_json(c.b_to_a)},
          {"diagonal", c.diagonal},
          {"a", topology_json(c.a)},
          {"b", topology_json(c.b)}};
}

}  // namespace scan2lod
