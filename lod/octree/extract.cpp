#include <scan2lod/lod/octree/extract.h>

#include <scan2lod/core/compact_mesh.h>

#include <omp.h>

#include <algorithm>
#include <array>
#include <cstring>

namespace scan2lod {
namespace {

// Marks in extract_lod's scratch: bit 0 expanded, bit 1 in the cut.
constexpr std::uint8_t kCut = 2;
constexpr std::uint64_t kCutInEight = 0x0202020202020202ull;  // kCut in each of eight flags

// Levels from this many expansions on are emitted by all cores.
constexpr std::size_t kParallelFrom = 1024;
constexpr int kChunks = 32;
// ... and from this many, their cut is marked by all cores too.
constexpr std::size_t kTeamMarksFrom = 8192;

// The first node (or LOD array entry) of chunk c of [0, total).
std::size_t chunk_begin(std::size_t total, int c) { return total * std::size_t(c) / kChunks; }

// Starts loading the neighbours transition_of reads.
void prefetch_neighbours(const McOctree& tree, std::size_t node) {
  if (node >= tree.internal_nodes()) return;
  const auto* around = tree.transitions.neighbours[node].data();
  __builtin_prefetch(around);
  __builtin_prefetch(around + 26);
}

// The transition input of a node of the cut, or false when it emits its own
// triangles (no finer node around it).
bool transition_of(const McOctree& tree, std::int32_t node, const std::vector<std::uint8_t>& expanded,
                   TransitionInput* in) {
  if (std::size_t(node) >= tree.internal_nodes()) return false;
  // A node beside expanded cells is triangulated against the finer nodes there.
  const auto& around = tree.transitions.neighbours[node];
  std::uint32_t splits = 0;
  // Branch-free: whether a cell is empty or expanded is as good as random.
  const std::uint8_t* flags = expanded.data();
  const auto& splits_by_cell = cell_splits();
  for (const int c : splitting_cells()) {
    const std::int32_t a = around[std::size_t(c)];
    const std::uint32_t fine = flags[std::max(a, 0)] & kExpanded & std::uint8_t(a >= 0);
    splits |= splits_by_cell[std::size_t(c)] & (0u - fine);
  }
  if (!splits) return false;
  const std::uint16_t edges = std::uint16_t(splits & 0xfff);
  const std::uint8_t faces = std::uint8_t(splits >> 12);
  *in = TransitionInput{tree.transitions.boundary_inside[node], tree.nodes.edge_vertices[node].data(),
                        tree.transitions.sub_edge_vertices[node].data(), tree.transitions.centre_vertices[node], faces, edges,
                        tree.transitions.straight_faces[node]};
  return true;
}

// Appends the triangles of the cut's nodes in [begin, end).
// - Nodes that emit their own triangles mostly sit next to each other with
//   their triangles stored back to back (siblings, and leaves in node order),
//   so runs of them go out as one copy: per-node inserts were a sixth of the
//   time at 100 %.
// - A transition's cached triangulation is a cache miss away; it is asked for
//   a few nodes ahead and emitted when its turn comes, in node order.
// With `blocks`, also appends each node and its triangle count there.
void emit_range(const McOctree& tree, const std::vector<std::uint8_t>& marks, std::size_t begin, std::size_t end,
                std::vector<Triangle>* triangles, std::vector<CutBlock>* blocks = nullptr) {
  const Triangle* own = tree.triangles.data();
  struct Pending {
    TransitionInput in;           // when run_end < 0
    std::int32_t run_begin = 0;   // else own triangles [run_begin, run_end)
    std::int32_t run_end = 0;
    std::size_t block = 0;        // a transition's entry in blocks
  };
  constexpr unsigned kAhead = 8;  // a power of two
  Pending queue[kAhead];
  unsigned head = 0, tail = 0;  // pending: [head, tail), modulo kAhead
  auto emit_front = [&] {
    const Pending& p = queue[head++ % kAhead];
    if (p.run_end < 0) {
      const std::size_t before = triangles->size();
      triangulate_transition(p.in, triangles);
      if (blocks) (*blocks)[p.block].count = std::int32_t(triangles->size() - before);
    } else
      triangles->insert(triangles->end(), own + p.run_begin, own + p.run_end);
  };
  auto push = [&]() -> Pending& {
    if (tail - head == kAhead) emit_front();
    return queue[tail++ % kAhead];
  };
  bool in_run = false;  // the newest pending entry is a run still growing
  // Nodes above the leaves read their neighbours, a miss each unless asked
  // for ahead.
  constexpr std::size_t kNeighboursAhead = 8;
  for (std::size_t node = begin; node < end; ++node) {
    // Eight flags at a time where none is in the cut: small levels are
    // mostly such runs, and the scan was most of their time.
    if ((node & 7) == 0 && node + 8 <= end) {
      std::uint64_t eight;
      std::memcpy(&eight, marks.data() + node, 8);
      if (!(eight & kCutInEight)) {
        node += 7;
        continue;
      }
    }
    if (node + kNeighboursAhead < end) prefetch_neighbours(tree, node + kNeighboursAhead);
    if (marks[node] != kCut) continue;
    TransitionInput in;
    if (transition_of(tree, std::int32_t(node), marks, &in)) {
      prefetch_transition(in);
      Pending& p = push();
      p.in = in;
      p.run_end = -1;
      in_run = false;
      if (blocks) {
        p.block = blocks->size();
        blocks->push_back({std::int32_t(node), 0});
      }
      continue;
    }
    const std::int32_t first = tree.nodes.first_triangle[node];
    if (blocks) blocks->push_back({std::int32_t(node), tree.nodes.triangle_counts[node]});
    Pending* last = in_run ? &queue[(tail - 1) % kAhead] : nullptr;
    if (!last || last->run_end != first) {
      last = &push();
      last->run_begin = first;
      in_run = true;
    }
    last->run_end = first + tree.nodes.triangle_counts[node];
  }
  while (head != tail) emit_front();
}

// mark_cut in two passes over entries [begin, end) of the LOD array; a pass
// over every entry must finish before the second starts. Each node is written
// by one entry in each pass (the parent of a cut node is the only expansion
// that marks it), so disjoint ranges can run at once.
void mark_expanded(const LodArray& lod, std::size_t begin, std::size_t end, std::uint8_t* flags) {
  for (std::size_t i = begin; i < end; ++i) flags[lod.order[i]] = kExpanded;
}

void mark_children(const McOctree& tree, const LodArray& lod, std::size_t begin, std::size_t end,
                   std::uint8_t* flags) {
  for (std::size_t i = begin; i < end; ++i) {
    const std::int32_t node = lod.order[i];
    for (std::int32_t c = tree.nodes.first_child[node], end_child = c + tree.nodes.child_counts[node]; c < end_child; ++c)
      if (!(flags[c] & kExpanded)) flags[c] = kCut;
  }
}


}  // namespace

void emit_cut(const McOctree& tree, const std::vector<std::uint8_t>& flags, std::vector<Triangle>* triangles,
              std::vector<CutBlock>* blocks) {
  emit_range(tree, flags, 0, tree.size(), triangles, blocks);
}

std::vector<Triangle> full_triangles(const McOctree& tree) {
  std::vector<Triangle> full;
  full.reserve(tree.triangles.size() + tree.patches.triangles.size());
  for (std::size_t node = 0; node < tree.size(); ++node)
    if (tree.is_leaf(node))
      full.insert(full.end(), tree.triangles.begin() + tree.nodes.first_triangle[node],
                  tree.triangles.begin() + tree.nodes.first_triangle[node] + tree.nodes.triangle_counts[node]);
  full.insert(full.end(), tree.patches.triangles.begin(), tree.patches.triangles.end());
  return full;
}

void emit_node(const McOctree& tree, std::int32_t node, const std::vector<std::uint8_t>& expanded,
               std::vector<Triangle>* triangles) {
  TransitionInput in;
  if (transition_of(tree, node, expanded, &in)) return triangulate_transition(in, triangles);
  const Triangle* first = tree.triangles.data() + tree.nodes.first_triangle[node];
  triangles->insert(triangles->end(), first, first + tree.nodes.triangle_counts[node]);
}

void prefetch_node(const McOctree& tree, std::int32_t node) {
  const std::size_t n = std::size_t(node);
  __builtin_prefetch(&tree.nodes.first_triangle[n]);
  if (n >= tree.internal_nodes()) return;
  prefetch_neighbours(tree, n);
  prefetch_crossings(tree.transitions.sub_edge_vertices[n].data(), tree.nodes.edge_vertices[n].data());
  __builtin_prefetch(&tree.transitions.boundary_inside[n]);
  __builtin_prefetch(&tree.transitions.centre_vertices[n]);
}

void node_triangle_counts(const McOctree& tree, const std::int32_t* nodes, int size,
                          const std::vector<std::uint8_t>& expanded, std::int32_t* counts) {
  constexpr int kBatch = 32;
  for (int first = 0; first < size; first += kBatch) {
    const int n = std::min(kBatch, size - first);
    const std::int32_t* batch = nodes + first;
    for (int i = 0; i < n; ++i) prefetch_neighbours(tree, std::size_t(batch[i]));
    TransitionInput inputs[kBatch];
    bool transition[kBatch];
    for (int i = 0; i < n; ++i)
      if ((transition[i] = transition_of(tree, batch[i], expanded, &inputs[i]))) prefetch_transition(inputs[i]);
    for (int i = 0; i < n; ++i)
      counts[first + i] =
          transition[i] ? transition_triangle_count(inputs[i]) : tree.nodes.triangle_counts[std::size_t(batch[i])];
  }
}

void mark_cut(const McOctree& tree, const LodArray& lod, std::size_t priority, std::uint8_t* flags) {
  if (priority == 0) flags[0] = kCut;
  mark_expanded(lod, 0, priority, flags);
  mark_children(tree, lod, 0, priority, flags);
}

void extract_lod(const McOctree& tree, const LodArray& lod, std::size_t priority,
                 std::vector<std::uint8_t>* expanded, std::vector<Triangle>* triangles) {
  priority = std::min(priority, lod.full());
  expanded->resize(tree.size(), 0);
  if (priority == 0) {
    triangles->clear();
    emit_node(tree, 0, *expanded, triangles);
    return;
  }
  std::uint8_t* flags = expanded->data();
  const std::vector<std::uint8_t>& marks = *expanded;
  // Hole patches show once every node around their rim has expanded.
  auto append_patches = [&] {
    for (std::size_t g = 0; g < tree.patch_groups(); ++g) {
      bool shown = true;
      for (std::int32_t k = tree.patches.needs_first[g]; k < tree.patches.needs_first[g + 1] && shown; ++k)
        shown = flags[tree.patches.needs[k]] & kExpanded;
      if (shown)
        triangles->insert(triangles->end(), tree.patches.triangles.begin() + tree.patches.group_first[g],
                          tree.patches.triangles.begin() + tree.patches.group_first[g + 1]);
    }
  };
  // The cut in node order rather than LOD order: neighbouring nodes' data sit
  // together, which made extraction up to 2x faster at levels with many
  // transitions; the scan over all node flags costs about as much as a copy.
  const std::size_t n = tree.size();
  if (priority < kParallelFrom || omp_get_max_threads() < 2) {
    mark_cut(tree, lod, priority, flags);
    triangles->clear();
    emit_range(tree, marks, 0, n, triangles);
    append_patches();
    std::fill(expanded->begin(), expanded->end(), 0);
    return;
  }
  // Chunks of the node range on every core, joined in order, so the output is
  // the same as one thread's. Transitions sit in the first quarter (nodes
  // above the leaves come first), hence many chunks, taken dynamically.
  thread_local std::vector<std::vector<Triangle>> kept;  // capacity kept between calls
  std::vector<std::vector<Triangle>>& parts = kept;       // this thread's, shared with the workers
  parts.resize(kChunks);
  std::size_t offsets[kChunks + 1];
  // One team for all of it: waking the workers, and every barrier, costs
  // tens of microseconds under OMP_WAIT_POLICY=passive. Small levels mark
  // their cut before the team starts, as two more barriers cost more than
  // marking on both cores saves there.
  const bool team_marks = priority >= kTeamMarksFrom;
  if (!team_marks) mark_cut(tree, lod, priority, flags);
#pragma omp parallel
  {
    if (team_marks) {
#pragma omp for schedule(static)
      for (int c = 0; c < kChunks; ++c)
        mark_expanded(lod, chunk_begin(priority, c), chunk_begin(priority, c + 1), flags);
#pragma omp for schedule(static)
      for (int c = 0; c < kChunks; ++c)
        mark_children(tree, lod, chunk_begin(priority, c), chunk_begin(priority, c + 1), flags);
    }
#pragma omp for schedule(dynamic, 1)
    for (int c = 0; c < kChunks; ++c) {
      std::vector<Triangle>& part = parts[std::size_t(c)];
      part.clear();
      emit_range(tree, marks, chunk_begin(n, c), chunk_begin(n, c + 1), &part);
    }
#pragma omp single
    {
      offsets[0] = 0;
      for (int c = 0; c < kChunks; ++c) offsets[c + 1] = offsets[c] + parts[std::size_t(c)].size();
      // Not cleared first: what a previous level left is overwritten rather
      // than zeroed and then overwritten.
      triangles->resize(offsets[kChunks]);
      append_patches();
    }
    // The join is a copy of the whole level, and the flags are cleared: on
    // every core too.
#pragma omp for schedule(static) nowait
    for (int c = 0; c < kChunks; ++c)
      std::copy(parts[std::size_t(c)].begin(), parts[std::size_t(c)].end(), triangles->begin() + std::ptrdiff_t(offsets[c]));
#pragma omp for schedule(static) nowait
    for (int c = 0; c < kChunks; ++c)
      std::fill(flags + chunk_begin(n, c), flags + chunk_begin(n, c + 1), 0);
  }
}

TriangleMesh compact_lod(const McOctree& tree, const std::vector<Triangle>& triangles) {
  std::vector<Triangle> out = triangles;
  const VertexArray& v = tree.vertices;
  TriangleMesh mesh = compact_mesh(v.positions, v.normals, v.colors, {&out});
  mesh.triangles = std::move(out);
  return mesh;
}

}  // namespace scan2lod
