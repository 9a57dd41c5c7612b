#include <scan2lod/core/mesh_edges.h>

#include <algorithm>

namespace scan2lod {

MeshEdges mesh_edges(const std::vector<Triangle>& triangles, std::size_t vertex_count) {
  // Sides bucketed by smaller vertex: first[v] .. first[v + 1].
  std::vector<std::int32_t> first(vertex_count + 1, 0);
  for (const Triangle& t : triangles)
    for (int k = 0; k < 3; ++k) ++first[std::size_t(std::min(t[k], t[(k + 1) % 3])) + 1];
  for (std::size_t v = 0; v < vertex_count; ++v) first[v + 1] += first[v];
  struct Side {
    std::int32_t other;  // the larger vertex
    std::int32_t side;   // triangle * 3 + k
  };
  std::vector<Side> sides(static_cast<std::size_t>(first[vertex_count]));  // not size_t(...): clang reads that as a declaration
  std::vector<std::int32_t> fill(first.begin(), first.end() - 1);
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = triangles[t][k], b = triangles[t][(k + 1) % 3];
      sides[std::size_t(fill[std::size_t(std::min(a, b))]++)] = {std::max(a, b), std::int32_t(3 * t + std::size_t(k))};
    }
  MeshEdges edges;
  edges.of_triangle.resize(triangles.size());
  edges.uses.reserve(triangles.size() * 3 / 2 + 1);
  edges.ends.reserve(triangles.size() * 3 / 2 + 1);
  for (std::size_t v = 0; v < vertex_count; ++v) {
    Side* begin = sides.data() + first[v];
    Side* end = sides.data() + first[v + 1];
    // A handful of sides per vertex.
    std::sort(begin, end, [](const Side& x, const Side& y) { return x.other < y.other; });
    for (Side* s = begin; s != end;) {
      const std::int32_t id = std::int32_t(edges.uses.size());
      Side* run = s;
      for (; run != end && run->other == s->other; ++run) edges.of_triangle[std::size_t(run->side / 3)][run->side % 3] = id;
      edges.uses.push_back(std::int32_t(run - s));
      edges.ends.push_back({std::int32_t(v), s->other});
      s = run;
    }
  }
  return edges;
}

double mean_edge_length(ArrayView<Vec3f> p, const std::vector<Triangle>& triangles, std::size_t stride) {
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < triangles.size(); i += stride, ++n) {
    const Triangle& t = triangles[i];
    for (int k = 0; k < 3; ++k) sum += (p[std::size_t(t[k])] - p[std::size_t(t[(k + 1) % 3])]).norm();
  }
  return n == 0 ? 0 : sum / double(3 * n);
}

}  // namespace scan2lod
