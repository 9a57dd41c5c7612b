#include <scan2lod/reconstruct/cube_table.h>

#include <Eigen/Core>

#include <cassert>
#include <vector>

namespace scan2lod {
namespace {

int corner_index(int x, int y, int z) { return x | (y << 1) | (z << 2); }


int edge_between(int a, int b) {
  for (int e = 0; e < 12; ++e)
    if ((edge_corner(e, 0) == a && edge_corner(e, 1) == b) ||
        (edge_corner(e, 0) == b && edge_corner(e, 1) == a))
      return e;
  assert(false);
  return -1;
}

// The four corners of a face, counter-clockwise seen from outside the cube.
std::array<int, 4> face_corners(int axis, int side) {
  int u = (axis + 1) % 3, v = (axis + 2) % 3;
  std::array<int, 4> out{};
  const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};  // CCW seen from +axis
  for (int k = 0; k < 4; ++k) {
    int o[3];
    o[axis] = side;
    o[u] = uv[k][0];
    o[v] = uv[k][1];
    out[side ? k : 3 - k] = corner_index(o[0], o[1], o[2]);
  }
  return out;
}

// Two cube edges share a face when they have a common corner or are opposite
// edges of one face: a diagonal between them would lie in that face, where the
// neighbouring cube may draw the same line, giving an edge of four triangles.
bool share_face(int e0, int e1) {
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      bool on0 = true, on1 = true;
      for (int end = 0; end < 2; ++end) {
        on0 &= ((edge_corner(e0, end) >> axis) & 1) == side;
        on1 &= ((edge_corner(e1, end) >> axis) & 1) == side;
      }
      if (on0 && on1) return true;
    }
  return false;
}

Eigen::Vector3f edge_midpoint(int e) {
  int a = edge_corner(e, 0);
  Eigen::Vector3f p(float(a & 1), float((a >> 1) & 1), float((a >> 2) & 1));
  p[e / 4] = 0.5f;
  return p;
}

// Triangulates a loop (inside on its left seen from outside the cube) with no
// diagonal inside a cube face, choosing among those the shortest total diagonal
// length (dynamic programming over polygon triangulations).
void triangulate_loop(const std::vector<int>& loop, CubeCase* out) {
  const int n = int(loop.size());
  constexpr float kInf = 1e30f;
  float cost[12][12];
  int split[12][12];
  auto allowed = [&](int i, int j) {
    return j - i == 1 || (i == 0 && j == n - 1) || !share_face(loop[i], loop[j]);
  };
  for (int gap = 1; gap < n; ++gap)
    for (int i = 0; i + gap < n; ++i) {
      int j = i + gap;
      cost[i][j] = gap == 1 ? 0.f : kInf;
      split[i][j] = -1;
      if (gap == 1 || !allowed(i, j)) continue;
      float length = (i == 0 && j == n - 1) ? 0.f : (edge_midpoint(loop[i]) - edge_midpoint(loop[j])).norm();
      for (int k = i + 1; k < j; ++k) {
        float c = cost[i][k] + cost[k][j] + length;
        if (c < cost[i][j]) cost[i][j] = c, split[i][j] = k;
      }
    }
  assert(cost[0][n - 1] < kInf && "every marching-cubes loop has a face-free triangulation");
  std::vector<std::pair<int, int>> stack = {{0, n - 1}};
  while (!stack.empty()) {
    auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    int k = split[i][j];
    // The loop runs clockwise around the outward normal; emit reversed.
    out->triangles[out->triangle_count++] = {std::uint8_t(loop[i]), std::uint8_t(loop[j]),
                                             std::uint8_t(loop[k])};
    stack.push_back({i, k});
    stack.push_back({k, j});
  }
}

CubeCase make_case(int mask) {
  auto inside = [&](int c) { return (mask >> c) & 1; };
  // next[e] = the crossing edge that follows e on its loop.
  int next[12];
  for (int& n : next) n = -1;
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      std::array<int, 4> c = face_corners(axis, side);
      // Each run of inside corners (CCW) is cut off by one segment, from the edge
      // that leaves the run to the edge that enters it. Separate runs stay separate,
      // which resolves an ambiguous face the same way from both of its cubes.
      for (int k = 0; k < 4; ++k) {
        int prev = (k + 3) % 4;
        if (!inside(c[k]) || inside(c[prev])) continue;  // k starts a run
        int end = k;
        while (inside(c[(end + 1) % 4])) end = (end + 1) % 4;
        int enter = edge_between(c[prev], c[k]);
        int leave = edge_between(c[end], c[(end + 1) % 4]);
        assert(next[leave] == -1);
        next[leave] = enter;
      }
    }
  }
  CubeCase out;
  bool seen[12] = {};
  for (int start = 0; start < 12; ++start) {
    if (next[start] < 0 || seen[start]) continue;
    std::vector<int> loop;
    for (int e = start; !seen[e]; e = next[e]) {
      seen[e] = true;
      loop.push_back(e);
      out.edge_mask |= std::uint16_t(1u << e);
    }
    triangulate_loop(loop, &out);
  }
  return out;
}

std::array<CubeCase, 256> make_table() {
  std::array<CubeCase, 256> table;
  for (int mask = 0; mask < 256; ++mask) table[mask] = make_case(mask);
  return table;
}

}  // namespace

const std::array<CubeCase, 256>& cube_cases() {
  static const std::array<CubeCase, 256> table = make_table();
  return table;
}


}  // namespace scan2lod
