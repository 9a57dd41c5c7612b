#include <scan2lod/lod/octree/transition.h>

#include <scan2lod/core/flat_hash.h>
#include <scan2lod/reconstruct/cube_table.h>

#include <algorithm>
#include <cstring>

namespace scan2lod {
namespace {

int lattice(int i, int j, int k) { return i + 3 * j + 9 * k; }

struct Tables {
  std::array<SubEdge, kSubEdges> sub_edges{};
  std::array<std::array<std::int8_t, 27>, 27> sub_edge_of{};  // local points -> sub-edge, or -1
  std::array<std::array<std::int8_t, 27>, 27> edge_of{};      // node corners' points -> node edge, or -1
  std::array<std::array<std::uint8_t, 9>, 6> face_points{};   // (u, v) grid on each face, index u + 3v
  std::array<bool, 6> face_reversed{};                        // side 0 faces wind the other way
  std::array<std::array<std::int8_t, 4>, 6> face_edges{};     // node edges around each face, CCW from (0,0)
  std::array<std::int8_t, 61> slot_line{};  // the node edge whose line holds a slot's crossing, or -1
  std::array<std::uint8_t, 61> slot_faces{};  // bit axis*2+side: the node faces holding a slot's crossing

  Tables() {
    for (auto& row : sub_edge_of) row.fill(-1);
    for (auto& row : edge_of) row.fill(-1);
    auto on_boundary = [](int i, int j, int k) { return i != 1 || j != 1 || k != 1; };
    int count = 0;
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i)
          for (int axis = 0; axis < 3; ++axis) {
            int q[3] = {i, j, k};
            if (q[axis] == 2) continue;
            int r[3] = {i, j, k};
            ++r[axis];
            // Both ends on one face of the node: some other coordinate is 0 or 2.
            bool face = false;
            for (int other = 0; other < 3; ++other)
              if (other != axis && (q[other] != 1)) face = true;
            if (!face || !on_boundary(q[0], q[1], q[2]) || !on_boundary(r[0], r[1], r[2])) continue;
            const int a = lattice(q[0], q[1], q[2]), b = lattice(r[0], r[1], r[2]);
            sub_edges[count] = {std::uint8_t(a), std::uint8_t(b)};
            sub_edge_of[a][b] = sub_edge_of[b][a] = std::int8_t(count);
            ++count;
          }
    for (int e = 0; e < 12; ++e) {
      const int a = lattice_of_corner(edge_corner(e, 0)), b = lattice_of_corner(edge_corner(e, 1));
      edge_of[a][b] = edge_of[b][a] = std::int8_t(e);
    }
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side) {
        const int f = axis * 2 + side, u = (axis + 1) % 3, v = (axis + 2) % 3;
        for (int pv = 0; pv < 3; ++pv)
          for (int pu = 0; pu < 3; ++pu) {
            int p[3];
            p[axis] = side * 2;
            p[u] = pu;
            p[v] = pv;
            face_points[f][pu + 3 * pv] = std::uint8_t(lattice(p[0], p[1], p[2]));
          }
        face_reversed[f] = side == 0;
        const int corners[4][2] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}};
        for (int k = 0; k < 4; ++k) {
          const int* c0 = corners[k];
          const int* c1 = corners[(k + 1) % 4];
          face_edges[f][k] = edge_of[face_points[f][c0[0] + 3 * c0[1]]][face_points[f][c1[0] + 3 * c1[1]]];
        }
      }
    // A sub-edge lies on a node edge's line when its other two coordinates
    // are both 0 or 2.
    slot_line.fill(-1);
    for (int k = 0; k < kSubEdges; ++k) {
      const int a = sub_edges[std::size_t(k)].a, b = sub_edges[std::size_t(k)].b;
      int pa[3] = {a % 3, a / 3 % 3, a / 9};
      const int pb[3] = {b % 3, b / 3 % 3, b / 9};
      int along = 0;
      while (pa[along] == pb[along]) ++along;
      bool on_line = true;
      for (int axis = 0; axis < 3; ++axis)
        if (axis != along && pa[axis] == 1) on_line = false;
      if (!on_line) continue;
      int lo[3] = {pa[0], pa[1], pa[2]}, hi[3] = {pa[0], pa[1], pa[2]};
      lo[along] = 0;
      hi[along] = 2;
      slot_line[std::size_t(k)] = edge_of[lattice(lo[0], lo[1], lo[2])][lattice(hi[0], hi[1], hi[2])];
    }
    for (int e = 0; e < 12; ++e) slot_line[std::size_t(kSubEdges + e)] = std::int8_t(e);
    // A crossing lies on the faces both ends of its (sub-)edge lie on.
    auto faces_of = [](int p) {
      const int c[3] = {p % 3, p / 3 % 3, p / 9};
      std::uint8_t bits = 0;
      for (int axis = 0; axis < 3; ++axis)
        if (c[axis] != 1) bits |= std::uint8_t(1u << (axis * 2 + c[axis] / 2));
      return bits;
    };
    for (int k = 0; k < kSubEdges; ++k)
      slot_faces[std::size_t(k)] = faces_of(sub_edges[std::size_t(k)].a) & faces_of(sub_edges[std::size_t(k)].b);
    for (int e = 0; e < 12; ++e)
      slot_faces[std::size_t(kSubEdges + e)] =
          faces_of(lattice_of_corner(edge_corner(e, 0))) & faces_of(lattice_of_corner(edge_corner(e, 1)));
  }
};

const Tables& tables() {
  static const Tables t;
  return t;
}

}  // namespace

const std::array<SubEdge, kSubEdges>& transition_sub_edges() { return tables().sub_edges; }

const std::array<int, 18>& splitting_cells() {
  static const auto cells = [] {
    std::array<int, 18> found{};
    int n = 0;
    for (int c = 0; c < 27; ++c) {
      const int offsets = (c % 3 != 1) + (c / 3 % 3 != 1) + (c / 9 != 1);
      if (offsets == 1 || offsets == 2) found[std::size_t(n++)] = c;
    }
    return found;
  }();
  return cells;
}

const std::array<std::uint32_t, 27>& cell_splits() {
  static const auto splits = [] {
    auto cell = [](int dx, int dy, int dz) { return (dx + 1) + 3 * (dy + 1) + 9 * (dz + 1); };
    std::array<std::uint32_t, 27> found{};
    for (int e = 0; e < 12; ++e) {
      const int axis = e / 4, u = (axis + 1) % 3, v = (axis + 2) % 3;
      int du[3] = {0, 0, 0}, dv[3] = {0, 0, 0};
      du[u] = (e & 1) ? 1 : -1;
      dv[v] = (e & 2) ? 1 : -1;
      for (const int c : {cell(du[0], du[1], du[2]), cell(dv[0], dv[1], dv[2]),
                          cell(du[0] + dv[0], du[1] + dv[1], du[2] + dv[2])})
        found[std::size_t(c)] |= 1u << e;
    }
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side) {
        int d[3] = {0, 0, 0};
        d[axis] = side ? 1 : -1;
        found[std::size_t(cell(d[0], d[1], d[2]))] |= 1u << (12 + axis * 2 + side);
      }
    return found;
  }();
  return splits;
}

int lattice_of_corner(int c) { return lattice((c & 1) * 2, ((c >> 1) & 1) * 2, ((c >> 2) & 1) * 2); }

namespace {

// A transition's triangles as crossing slots (0..47 sub-edges, 48..59 node
// edges, 60 the centre): they depend on the signs and refinement alone.
constexpr int kCentreSlot = 60;
constexpr int kMaxTransitionTriangles = 64;
struct SlotTriangles {
  std::uint8_t count = 0;
  std::uint8_t slots[kMaxTransitionTriangles][3];
};

// Builds the slot triangles of one configuration.
void transition_slots(const TransitionInput& in, SlotTriangles* result) {
  const Tables& T = tables();
  // Crossing slots: 0..47 sub-edges, 48..59 whole node edges.
  std::int8_t next[60];
  std::fill(next, next + 60, -1);
  auto slot = [&](int p, int q) -> int {
    const int s = T.sub_edge_of[p][q];
    return s >= 0 ? s : kSubEdges + T.edge_of[p][q];
  };
  auto inside = [&](int p) { return (in.inside >> p) & 1; };
  // Joins one polygon's crossings: each run of inside points is cut off by a
  // segment from the crossing that leaves it to the one that enters it.
  auto join = [&](const int* poly, int m, bool reversed) {
    int order[8];
    for (int k = 0; k < m; ++k) order[k] = poly[reversed ? m - 1 - k : k];
    for (int k = 0; k < m; ++k) {
      const int prev = (k + m - 1) % m;
      if (!inside(order[k]) || inside(order[prev])) continue;
      int end = k;
      while (inside(order[(end + 1) % m])) end = (end + 1) % m;
      next[slot(order[end], order[(end + 1) % m])] = std::int8_t(slot(order[prev], order[k]));
    }
  };
  for (int f = 0; f < 6; ++f) {
    const auto& P = T.face_points[f];
    if ((in.fine_faces >> f) & 1) {
      for (int qv = 0; qv < 2; ++qv)
        for (int qu = 0; qu < 2; ++qu) {
          const int quad[4] = {P[qu + 3 * qv], P[qu + 1 + 3 * qv], P[qu + 1 + 3 * (qv + 1)], P[qu + 3 * (qv + 1)]};
          join(quad, 4, T.face_reversed[f]);
        }
    } else {
      const int corners[4][2] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}};
      int poly[8], m = 0;
      for (int k = 0; k < 4; ++k) {
        poly[m++] = P[corners[k][0] + 3 * corners[k][1]];
        if ((in.split_edges >> T.face_edges[f][k]) & 1) {
          const int mu = (corners[k][0] + corners[(k + 1) % 4][0]) / 2, mv = (corners[k][1] + corners[(k + 1) % 4][1]) / 2;
          poly[m++] = P[mu + 3 * mv];
        }
      }
      join(poly, m, T.face_reversed[f]);
    }
  }
  result->count = 0;
  auto add = [&](int a, int b, int c) {
    if (result->count == kMaxTransitionTriangles) return;  // 60 crossings make at most 60 fan triangles
    std::uint8_t* t = result->slots[result->count++];
    t[0] = std::uint8_t(a), t[1] = std::uint8_t(b), t[2] = std::uint8_t(c);
  };
  bool seen[60] = {};
  int loops[60];  // the loops' slots, one after another
  int loop_first[31] = {0}, loop_count = 0;
  for (int start = 0; start < 60; ++start) {
    if (next[start] < 0 || seen[start]) continue;
    int end = loop_first[loop_count];
    for (int s = start; s >= 0 && !seen[s]; s = next[s]) seen[s] = true, loops[end++] = s;
    loop_first[++loop_count] = end;
  }
  // The centre was fitted to the node's surface, one sheet: it goes to the
  // longest loop. Others (a second sheet through the node, or a small loop
  // around a refined midpoint) are fanned from a crossing of their own, so no
  // two sheets meet at the centre (a pinched vertex) and no fan reaches over
  // from a centre placed for another sheet (a fold). That crossing must not
  // share a node edge's line with another crossing of the loop: a diagonal
  // along a node edge is a segment of the nodes around that edge (an edge of
  // three or four triangles). Without such a crossing the loop takes the
  // centre too.
  int centred = -1;
  for (int l = 0; l < loop_count; ++l)
    if (loop_first[l + 1] - loop_first[l] > 3 &&
        (centred < 0 || loop_first[l + 1] - loop_first[l] > loop_first[centred + 1] - loop_first[centred]))
      centred = l;
  // Better still, no fan triangle lies on one node face: its three
  // crossings then lie where that face's plane meets the surface, on one line
  // wherever the surface is flat (a box face parallel to the lattice gave
  // triangles of no area at all). Where every apex has such a triangle, one
  // whose triangles lie on faces whose crossings are not in line
  // (straight_faces) is taken; failing that, the centre, as for a loop
  // without a clear crossing.
  auto apex_of = [&](const int* loop, int m) {
    int fallback = -1;
    for (int k = 0; k < m; ++k) {
      bool clear = true;
      const int line = T.slot_line[std::size_t(loop[k])];
      for (int j = 2; j + 1 < m && clear && line >= 0; ++j) clear = T.slot_line[std::size_t(loop[(k + j) % m])] != line;
      if (!clear) continue;
      std::uint8_t flat = 0;  // the faces that hold a fan triangle whole
      for (int j = 1; j + 1 < m; ++j)
        flat |= T.slot_faces[std::size_t(loop[k])] & T.slot_faces[std::size_t(loop[(k + j) % m])] &
                T.slot_faces[std::size_t(loop[(k + j + 1) % m])];
      if (!flat) return k;
      if (fallback < 0 && !(flat & in.straight_faces)) fallback = k;
    }
    return fallback;
  };
  for (int l = 0; l < loop_count; ++l) {
    const int* loop = loops + loop_first[l];
    const int m = loop_first[l + 1] - loop_first[l];
    // Two segments between the same two crossings (a single inside midpoint
    // pinched off on a split edge) enclose nothing: the two neighbours beyond
    // those faces already share that edge.
    if (m == 2) continue;
    // Loops run clockwise around the outward normal (as in cube_table.cpp): emit reversed.
    const int apex = l == centred ? -1 : apex_of(loop, m);
    if (apex < 0) {
      for (int k = 0; k < m; ++k) add(kCentreSlot, loop[(k + 1) % m], loop[k]);
    } else {
      for (int k = 1; k + 1 < m; ++k) add(loop[apex], loop[(apex + k + 1) % m], loop[(apex + k) % m]);
    }
  }
}

// The lattice points whose signs the triangulation reads: the corners, the
// midpoints of split edges and the points of fine faces; by tables of four
// edges and of the six faces at a time.
std::uint32_t used_points(const TransitionInput& in) {
  static const auto masks = [] {
    struct Masks {
      std::uint32_t corners = 0;
      std::array<std::array<std::uint32_t, 16>, 3> edge_mids{};
      std::array<std::uint32_t, 64> faces{};
    } m;
    const Tables& T = tables();
    for (int c = 0; c < 8; ++c) m.corners |= 1u << lattice_of_corner(c);
    for (int e = 0; e < 12; ++e) {
      const std::uint32_t mid = 1u << ((lattice_of_corner(edge_corner(e, 0)) + lattice_of_corner(edge_corner(e, 1))) / 2);
      for (int bits = 0; bits < 16; ++bits)
        if ((bits >> (e % 4)) & 1) m.edge_mids[std::size_t(e / 4)][std::size_t(bits)] |= mid;
    }
    for (int f = 0; f < 6; ++f)
      for (int bits = 0; bits < 64; ++bits)
        if ((bits >> f) & 1)
          for (int p : T.face_points[f]) m.faces[std::size_t(bits)] |= 1u << p;
    return m;
  }();
  return masks.corners | masks.edge_mids[0][in.split_edges & 15] | masks.edge_mids[1][(in.split_edges >> 4) & 15] |
         masks.edge_mids[2][(in.split_edges >> 8) & 15] | masks.faces[in.fine_faces & 63];
}

// Configurations repeat (a flat stretch of surface gives the same signs node
// after node), so each thread keeps every one it has built, packed: a count
// and the slot triples, 1 + 3 x count bytes, which the emit loop reads in one
// or two cache lines (a fixed 200-byte entry per hash slot was slower at every
// level than this, though it missed no more often).
struct Memo {
  FlatHashMap offsets{1 << 14};
  std::vector<std::uint8_t> packed;
};
thread_local Memo memo;

std::uint64_t memo_key(const TransitionInput& in) {
  return std::uint64_t(in.inside & used_points(in)) | std::uint64_t(in.fine_faces & 63) << 27 |
         std::uint64_t(in.split_edges & 4095) << 33 | std::uint64_t(in.straight_faces & 63) << 45;
}

const std::uint8_t* cached_slots(const TransitionInput& in) {
  constexpr std::size_t kMaxPacked = std::size_t(16) << 20;  // start over beyond this
  const std::uint64_t key = memo_key(in);
  std::int32_t at = memo.offsets.find(key);
  if (at < 0) {
    if (memo.packed.size() > kMaxPacked) memo = Memo{};
    SlotTriangles built;
    transition_slots(in, &built);
    at = std::int32_t(memo.packed.size());
    memo.packed.push_back(built.count);
    memo.packed.insert(memo.packed.end(), &built.slots[0][0], &built.slots[0][0] + 3 * built.count);
    memo.offsets.insert(key, at);
  }
  return memo.packed.data() + at;
}

}  // namespace

std::uint8_t straight_faces(const std::int32_t* edge_vertices, const std::int32_t* sub_edge_vertices,
                            const Vec3f* positions) {
  const Tables& T = tables();
  // Crossings one triangulation can hold together: a whole node edge's is
  // never beside its halves' (the edge is split or not), nor beside those
  // inside a face (a finer face splits its edges).
  auto together = [&](int s, int t) {
    if (s > t) std::swap(s, t);
    if (t < kSubEdges || s >= kSubEdges) return true;
    return T.slot_line[std::size_t(s)] >= 0 && T.slot_line[std::size_t(s)] != T.slot_line[std::size_t(t)];
  };
  static const auto on_face = [] {  // bit slot: the slot's crossing lies on face f
    std::array<std::uint64_t, 6> masks{};
    for (int slot = 0; slot < kCentreSlot; ++slot)
      for (int f = 0; f < 6; ++f)
        if ((tables().slot_faces[std::size_t(slot)] >> f) & 1) masks[std::size_t(f)] |= std::uint64_t(1) << slot;
    return masks;
  }();
  auto vertex = [&](int slot) { return slot < kSubEdges ? sub_edge_vertices[slot] : edge_vertices[slot - kSubEdges]; };
  std::uint64_t present = 0;
  for (int slot = 0; slot < kCentreSlot; ++slot) present |= std::uint64_t(vertex(slot) >= 0) << slot;
  std::uint8_t straight = 0;
  for (int f = 0; f < 6; ++f) {
    std::uint64_t here = present & on_face[std::size_t(f)];
    if (__builtin_popcountll(here) < 3) continue;
    int slots[kCentreSlot];
    const Vec3f* at[kCentreSlot];
    int count = 0;
    for (; here; here &= here - 1, ++count) {
      slots[count] = __builtin_ctzll(here);
      at[count] = &positions[vertex(slots[count])];
    }
    bool found = false;
    for (int a = 0; a < count && !found; ++a)
      for (int b = a + 1; b < count && !found; ++b) {
        if (!together(slots[a], slots[b])) continue;
        for (int c = b + 1; c < count && !found; ++c)
          found = together(slots[a], slots[c]) && together(slots[b], slots[c]) && in_line(*at[a], *at[b], *at[c]);
      }
    if (found) straight |= std::uint8_t(1u << f);
  }
  return straight;
}

void prefetch_crossings(const std::int32_t* sub_edge_vertices, const std::int32_t* edge_vertices) {
  const char* sub = reinterpret_cast<const char*>(sub_edge_vertices);
  for (int at = 0; at < kSubEdges * 4 + 64; at += 64) __builtin_prefetch(sub + at);
  __builtin_prefetch(edge_vertices);
  __builtin_prefetch(edge_vertices + 11);
}

void prefetch_transition(const TransitionInput& in) {
  memo.offsets.prefetch(memo_key(in));
  prefetch_crossings(in.sub_edge_vertices, in.edge_vertices);
}

int transition_triangle_count(const TransitionInput& in) { return cached_slots(in)[0]; }

void triangulate_transition(const TransitionInput& in, std::vector<Triangle>* out) {
  const std::uint8_t* entry = cached_slots(in);
  const int count = entry[0];
  const std::uint8_t* slots = entry + 1;
  // Slot -> vertex as one table: choosing among three arrays per corner
  // mispredicted often enough to cost more than the copy (and gathering only
  // the slots an entry uses was slower still).
  // Fixed-size copies, which the compiler inlines: std::copy_n went through
  // memmove, which cost more than the rest of this function.
  std::int32_t vertex[kCentreSlot + 1];
  std::memcpy(vertex, in.sub_edge_vertices, sizeof(std::int32_t) * kSubEdges);
  std::memcpy(vertex + kSubEdges, in.edge_vertices, sizeof(std::int32_t) * 12);
  vertex[kCentreSlot] = in.centre;
  for (int i = 0; i < count; ++i, slots += 3) out->push_back({vertex[slots[0]], vertex[slots[1]], vertex[slots[2]]});
}

}  // namespace scan2lod
