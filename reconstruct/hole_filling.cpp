#include <scan2lod/reconstruct/hole_filling.h>

#include <scan2lod/core/flat_hash.h>

#include <algorithm>
#include <limits>
#include <unordered_set>

namespace scan2lod {
namespace {

// Minimum-area triangulation of the polygon loop[0..n) (dynamic programming
// over polygon triangulations, O(n^3)), with the fewest flat triangles first:
// a marching-cubes rim runs straight along lattice lines, and three of its
// vertices on one line make a triangle of no area, the cheapest there is,
// which ray casters and normals cannot use (the virtually scanned bunny at
// R = 128 had one). Triangles are written reversed to the loop, which runs
// along the existing triangles' half-edges.
bool triangulate(const TriangleMesh& mesh, const std::vector<std::int32_t>& loop,
                 const std::unordered_set<std::uint64_t>& edges, std::vector<Triangle>* out) {
  const int n = int(loop.size());
  // (flat triangles, area), compared in that order.
  using Cost = std::pair<int, double>;
  const Cost kNone{std::numeric_limits<int>::max(), 0.0};
  std::vector<Cost> cost(std::size_t(n) * n, kNone);
  std::vector<int> split(std::size_t(n) * n, -1);
  auto at = [n](int i, int j) { return std::size_t(i) * n + j; };
  auto weight = [&](int i, int k, int j) {
    const Vec3f& a = mesh.positions[loop[i]];
    const Vec3f& b = mesh.positions[loop[k]];
    const Vec3f& c = mesh.positions[loop[j]];
    const double twice_area = double((b - a).cross(c - a).norm());
    return Cost{in_line(a, b, c) ? 1 : 0, 0.5 * twice_area};
  };
  for (int i = 0; i + 1 < n; ++i) cost[at(i, i + 1)] = Cost{0, 0.0};
  for (int gap = 2; gap < n; ++gap)
    for (int i = 0; i + gap < n; ++i) {
      const int j = i + gap;
      // A diagonal that is already an edge of the mesh would get a third triangle.
      if (!(i == 0 && j == n - 1) && edges.count(edge_key(loop[i], loop[j]))) continue;
      for (int k = i + 1; k < j; ++k) {
        const Cost& left = cost[at(i, k)];
        const Cost& right = cost[at(k, j)];
        if (left == kNone || right == kNone) continue;
        const Cost w = weight(i, k, j);
        const Cost c{left.first + right.first + w.first, left.second + right.second + w.second};
        if (c < cost[at(i, j)]) cost[at(i, j)] = c, split[at(i, j)] = k;
      }
    }
  if (cost[at(0, n - 1)] == kNone) return false;
  std::vector<std::pair<int, int>> stack = {{0, n - 1}};
  while (!stack.empty()) {
    auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    const int k = split[at(i, j)];
    out->push_back({loop[i], loop[j], loop[k]});
    stack.push_back({i, k});
    stack.push_back({k, j});
  }
  return true;
}

}  // namespace

std::vector<Triangle> fill_small_holes(const TriangleMesh& mesh, std::size_t max_edges) {
  // Boundary half-edges: a -> b used by one triangle, in its orientation.
  std::vector<std::pair<std::uint64_t, std::array<std::int32_t, 2>>> half;
  half.reserve(mesh.triangles.size() * 3);
  for (const Triangle& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) half.push_back({edge_key(t[k], t[(k + 1) % 3]), {t[k], t[(k + 1) % 3]}});
  std::sort(half.begin(), half.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<std::array<std::int32_t, 2>> boundary;
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    while (j < half.size() && half[j].first == half[i].first) ++j;
    if (j - i == 1) boundary.push_back(half[i].second);
    i = j;
  }
  return fill_small_holes(mesh, boundary, max_edges);
}

std::vector<Triangle> fill_small_holes(const TriangleMesh& mesh,
                                       const std::vector<std::array<std::int32_t, 2>>& boundary,
                                       std::size_t max_edges) {
  // The boundary's vertices, numbered locally, with the edge leaving each.
  FlatHashMap local(boundary.size() * 2 + 16);
  std::vector<std::int32_t> vertex, next;
  std::vector<std::uint8_t> pinched;
  auto local_id = [&](std::int32_t v) {
    const std::int32_t fresh = std::int32_t(vertex.size());
    const std::int32_t id = local.insert(std::uint64_t(std::uint32_t(v)), fresh);
    if (id == fresh) vertex.push_back(v), next.push_back(-1), pinched.push_back(0);
    return id;
  };
  for (const auto& [a, b] : boundary) {
    const std::int32_t la = local_id(a), lb = local_id(b);
    if (next[la] >= 0) pinched[la] = 1;  // two boundary edges leave a: ambiguous loop
    next[la] = lb;
  }
  // Closed, unpinched loops of a size to fill.
  std::vector<std::vector<std::int32_t>> loops;
  std::vector<std::uint8_t> seen(vertex.size(), 0);
  for (std::size_t start = 0; start < vertex.size(); ++start) {
    if (next[start] < 0 || seen[start]) continue;
    std::vector<std::int32_t> loop;
    bool usable = true;
    std::int32_t v = std::int32_t(start);
    while (v >= 0 && !seen[v]) {
      seen[v] = 1;
      usable &= !pinched[v];
      loop.push_back(vertex[v]);
      v = next[v];
    }
    if (v != std::int32_t(start) || !usable || loop.size() < 3 || loop.size() > max_edges) continue;
    // Starting at the least position, a loop is cut the same way whatever
    // order its edges came in and however its vertices are numbered (a flat
    // loop has many triangulations of equal area; bricks must pick in-core's).
    const auto least = std::min_element(loop.begin(), loop.end(), [&](std::int32_t a, std::int32_t b) {
      const Vec3f &p = mesh.positions[a], &q = mesh.positions[b];
      return std::lexicographical_compare(p.data(), p.data() + 3, q.data(), q.data() + 3);
    });
    std::rotate(loop.begin(), least, loop.end());
    loops.push_back(std::move(loop));
  }
  if (loops.empty()) return {};
  // The mesh edges between loop vertices: a diagonal that already is one
  // would get a third triangle.
  std::vector<std::uint8_t> on_loop(mesh.positions.size(), 0);
  for (const auto& loop : loops)
    for (std::int32_t v : loop) on_loop[v] = 1;
  std::unordered_set<std::uint64_t> edges;
  for (const Triangle& t : mesh.triangles)
    for (int k = 0; k < 3; ++k)
      if (on_loop[t[k]] && on_loop[t[(k + 1) % 3]]) edges.insert(edge_key(t[k], t[(k + 1) % 3]));
  std::vector<Triangle> patch;
  for (const auto& loop : loops) triangulate(mesh, loop, edges, &patch);
  return patch;
}

}  // namespace scan2lod
