#include "lod/extract.h"

#include <omp.h>

#include <algorithm>
#include <array>

namespace scan2lod {
namespace {

int cell(int dx, int dy, int dz) { return (dx + 1) + 3 * (dy + 1) + 9 * (dz + 1); }

// The cell across each face (axis * 2 + side) of a node.
const int kFaceCell[6] = {cell(-1, 0, 0), cell(1, 0, 0), cell(0, -1, 0), cell(0, 1, 0), cell(0, 0, -1), cell(0, 0, 1)};

// The three cells around each node edge (numbering of cube_table.h), as a
// mask of cells.
const auto kEdgeCells = [] {
  std::array<std::uint32_t, 12> cells{};
  for (int e = 0; e < 12; ++e) {
    const int axis = e / 4, u = (axis + 1) % 3, v = (axis + 2) % 3;
    int du[3] = {0, 0, 0}, dv[3] = {0, 0, 0};
    du[u] = (e & 1) ? 1 : -1;
    dv[v] = (e & 2) ? 1 : -1;
    cells[e] = (1u << cell(du[0], du[1], du[2])) | (1u << cell(dv[0], dv[1], dv[2])) |
               (1u << cell(du[0] + dv[0], du[1] + dv[1], du[2] + dv[2]));
  }
  return cells;
}();

// Marks in extract_lod's scratch: bit 0 expanded, bit 1 in the cut.
constexpr std::uint8_t kExpanded = 1, kCut = 2;

// Levels from this many expansions on are emitted by all cores.
constexpr std::size_t kParallelFrom = 1024;
constexpr int kChunks = 32;

}  // namespace

namespace {

// The transition input of a node of the cut, or false when it emits its own
// triangles (no finer node around it).
bool transition_of(const McOctree& tree, std::int32_t node, const std::vector<std::uint8_t>& expanded,
                   TransitionInput* in) {
  if (std::size_t(node) >= tree.internal_nodes()) return false;
  // A node beside expanded cells is triangulated against the finer nodes there.
  const auto& around = tree.neighbours[node];
  std::uint32_t fine = 0;
  // Branch-free: whether a cell is empty or expanded is as good as random.
  const std::uint8_t* flags = expanded.data();
  for (int c = 0; c < 27; ++c) {
    const std::int32_t a = around[c];
    fine |= std::uint32_t(flags[std::max(a, 0)] & kExpanded & std::uint8_t(a >= 0)) << c;
  }
  fine &= ~(1u << 13);  // the node itself
  if (!fine) return false;
  std::uint16_t edges = 0;
  for (int e = 0; e < 12; ++e)
    if (fine & kEdgeCells[e]) edges |= std::uint16_t(1u << e);
  if (!edges) return false;
  std::uint8_t faces = 0;
  for (int f = 0; f < 6; ++f) faces |= std::uint8_t((fine >> kFaceCell[f]) & 1) << f;
  *in = TransitionInput{tree.boundary_inside[node], tree.edge_vertices[node].data(),
                        tree.sub_edge_vertices[node].data(), tree.centre_vertices[node], faces, edges};
  return true;
}

}  // namespace

void emit_node(const McOctree& tree, std::int32_t node, const std::vector<std::uint8_t>& expanded,
               std::vector<Triangle>* triangles) {
  TransitionInput in;
  if (transition_of(tree, node, expanded, &in)) return triangulate_transition(in, triangles);
  const Triangle* first = tree.triangles.data() + tree.first_triangle[node];
  triangles->insert(triangles->end(), first, first + tree.triangle_counts[node]);
}

int node_triangle_count(const McOctree& tree, std::int32_t node, const std::vector<std::uint8_t>& expanded) {
  TransitionInput in;
  return transition_of(tree, node, expanded, &in) ? transition_triangle_count(in) : tree.triangle_counts[node];
}

void mark_cut(const McOctree& tree, const LodArray& lod, std::size_t priority, std::uint8_t* flags) {
  if (priority == 0) flags[0] = kCut;
  for (std::size_t i = 0; i < priority; ++i) flags[lod.order[i]] = kExpanded;
  for (std::size_t i = 0; i < priority; ++i) {
    const std::int32_t node = lod.order[i];
    for (std::int32_t c = tree.first_child[node], end = c + tree.child_counts[node]; c < end; ++c)
      if (!(flags[c] & kExpanded)) flags[c] = kCut;
  }
}

void extract_lod(const McOctree& tree, const LodArray& lod, std::size_t priority,
                 std::vector<std::uint8_t>* expanded, std::vector<Triangle>* triangles) {
  priority = std::min(priority, lod.full());
  triangles->clear();
  expanded->resize(tree.size(), 0);
  auto emit = [&](std::int32_t node) { emit_node(tree, node, *expanded, triangles); };
  if (priority == 0) {
    emit(0);
    return;
  }
  std::uint8_t* flags = expanded->data();
  mark_cut(tree, lod, priority, flags);
  // The cut in node order rather than LOD order: neighbouring nodes' data sit
  // together, which made extraction up to 2x faster at levels with many
  // transitions; the scan over all node flags costs about as much as a copy.
  const std::size_t n = tree.size();
  if (priority < kParallelFrom || omp_get_max_threads() < 2) {
    for (std::size_t node = 0; node < n; ++node)
      if (flags[node] == kCut) emit(std::int32_t(node));
  } else {
    // Chunks of the node range on every core, joined in order, so the output
    // is the same as one thread's. Transitions sit in the first quarter (nodes
    // above the leaves come first), hence many chunks, taken dynamically.
    thread_local std::vector<std::vector<Triangle>> kept;  // capacity kept between calls
    std::vector<std::vector<Triangle>>& parts = kept;       // this thread's, shared with the workers
    parts.resize(kChunks);
    const std::vector<std::uint8_t>& marks = *expanded;
#pragma omp parallel for schedule(dynamic, 1)
    for (int c = 0; c < kChunks; ++c) {
      std::vector<Triangle>& part = parts[std::size_t(c)];
      part.clear();
      for (std::size_t node = n * std::size_t(c) / kChunks, end = n * std::size_t(c + 1) / kChunks; node < end; ++node)
        if (marks[node] == kCut) emit_node(tree, std::int32_t(node), marks, &part);
    }
    std::size_t total = 0;
    for (const auto& part : parts) total += part.size();
    triangles->reserve(total);
    for (const auto& part : parts) triangles->insert(triangles->end(), part.begin(), part.end());
  }
  for (std::size_t g = 0; g < tree.patch_groups(); ++g) {
    bool shown = true;
    for (std::int32_t k = tree.patch_needs_first[g]; k < tree.patch_needs_first[g + 1] && shown; ++k)
      shown = flags[tree.patch_needs[k]] & kExpanded;
    if (shown)
      triangles->insert(triangles->end(), tree.patch_triangles.begin() + tree.patch_group_first[g],
                        tree.patch_triangles.begin() + tree.patch_group_first[g + 1]);
  }
  std::fill(expanded->begin(), expanded->end(), 0);
}

TriangleMesh compact_lod(const McOctree& tree, const std::vector<Triangle>& triangles) {
  TriangleMesh mesh;
  std::vector<std::int32_t> remap(tree.positions.size(), -1);
  mesh.triangles.reserve(triangles.size());
  for (const Triangle& t : triangles) {
    Triangle out;
    for (int k = 0; k < 3; ++k) {
      std::int32_t& r = remap[t[k]];
      if (r < 0) {
        r = std::int32_t(mesh.positions.size());
        mesh.positions.push_back(tree.positions[t[k]]);
        if (!tree.normals.empty()) mesh.normals.push_back(tree.normals[t[k]]);
        if (!tree.colors.empty()) mesh.colors.push_back(tree.colors[t[k]]);
      }
      out[k] = r;
    }
    mesh.triangles.push_back(out);
  }
  return mesh;
}

}  // namespace scan2lod
