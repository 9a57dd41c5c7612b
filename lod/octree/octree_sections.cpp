// The octree's part of the model file (lod/model_file.h lists its sections
// format by format): the grid, the tree packed (lod/octree/model_pack.h) or,
// in format 3, whole, crack patching, hole patches and the LOD array, and the
// checks that keep extract_lod and compact_lod in bounds on a loaded model.
#include <scan2lod/lod/octree/octree_sections.h>

#include <scan2lod/lod/octree/model_pack.h>
#include <scan2lod/lod/octree/transition.h>
#include <scan2lod/reconstruct/cube_table.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

namespace scan2lod {

static_assert(sizeof(std::array<std::int32_t, 12>) == 48 &&
                  sizeof(std::array<std::int32_t, kSubEdges>) == 4 * kSubEdges &&
                  sizeof(std::array<std::int32_t, 27>) == 108,
              "McOctree element types must be packed for the .mco layout");

namespace {

constexpr std::size_t kGridRecordBytes = 48;

OctreeNodes& nodes_of(LodModel& m) { return m.octree->tree.nodes; }
OctreeTransitions& transitions_of(LodModel& m) { return m.octree->tree.transitions; }
OctreePatches& patches_of(LodModel& m) { return m.octree->tree.patches; }

void check_octree_arrays(const SectionReader& file, const McOctree& t);
std::size_t check_nodes(const SectionReader& file, const McOctree& t);
void check_transitions(const SectionReader& file, const McOctree& t, std::size_t internal);
void check_lod_array(const SectionReader& file, const McOctree& t, const LodArray& lod, std::size_t internal);

class OctreeSections final : public StructureSections {
 public:
  std::vector<SectionRow> rows() override {
    return {
      {"GRID", true, [this](LodModel&) { return record(grid_, kGridRecordBytes); }},
      {"KEYS", true, [](LodModel& m) { return array(nodes_of(m).keys); }, 2, kUnpacked},
      {"LEVL", true, [](LodModel& m) { return array(nodes_of(m).levels); }, 2, kUnpacked},
      {"PRNT", true, [](LodModel& m) { return array(nodes_of(m).parents); }, 2, kUnpacked},
      {"FCHD", true, [](LodModel& m) { return array(nodes_of(m).first_child); }, 2, kUnpacked},
      {"NCHD", true, [](LodModel& m) { return array(nodes_of(m).child_counts); }, 2, kUnpacked},
      {"CHLD", true, [this](LodModel&) { return array(packed_.child_masks); }, kPacked},
      {"CASE", true, [](LodModel& m) { return array(nodes_of(m).cases); }},
      {"EDGV", true, [](LodModel& m) { return array(nodes_of(m).edge_vertices); }, 2, kUnpacked},
      {"EDGM", true, [this](LodModel&) { return array(packed_.edge_masks); }, kPacked},
      {"EDGP", true, [this](LodModel&) { return array(packed_.edge_vertices); }, kPacked},
      {"FTRI", true, [](LodModel& m) { return array(nodes_of(m).first_triangle); }, 2, kUnpacked},
      {"NTRI", true, [](LodModel& m) { return array(nodes_of(m).triangle_counts); }, 2, kUnpacked},
      {"TMSK", true, [this](LodModel&) { return array(packed_.triangle_masks); }, kPacked},
      {"METR", true, [](LodModel& m) { return array(nodes_of(m).metrics); }},
      {"BINS", true, [](LodModel& m) { return array(transitions_of(m).boundary_inside); }},
      {"SUBV", true, [](LodModel& m) { return array(transitions_of(m).sub_edge_vertices); }, 2, kUnpacked},
      {"SUBM", true, [this](LodModel&) { return array(packed_.sub_edge_masks); }, kPacked},
      {"SUBP", true, [this](LodModel&) { return array(packed_.sub_edge_vertices); }, kPacked},
      {"CNTR", true, [](LodModel& m) { return array(transitions_of(m).centre_vertices); }},
      {"NBRS", true, [](LodModel& m) { return array(transitions_of(m).neighbours); }, 2, kUnpacked},
      {"TRIS", true, [](LodModel& m) { return array(m.octree->tree.triangles); }, 2, kUnpacked},
      {"PTRI", true, [](LodModel& m) { return array(patches_of(m).triangles); }},
      {"PGRP", true, [](LodModel& m) { return array(patches_of(m).group_first); }},
      {"PNDF", true, [](LodModel& m) { return array(patches_of(m).needs_first); }},
      {"PNDS", true, [](LodModel& m) { return array(patches_of(m).needs); }},
      {"LODO", true, [](LodModel& m) { return array(m.octree->lod.order); }},
      {"LODA", true, [](LodModel& m) { return array(m.octree->lod.accumulated); }},
      // 1.1, optional: older readers offer levels inside it.
      {"PINC", false, [this](LodModel&) { return record(&pinned_, 8); }},
      // 4.1, optional: older readers offer levels inside the coarsening's steps.
      {"STEP", false, [](LodModel& m) { return array(m.octree->lod.inside_steps); }},
      // 4.2, optional: older files were counted without it (all zero).
      {"STRF", false, [](LodModel& m) { return array(transitions_of(m).straight_faces); }},
      // 4.3, optional: older readers cut the internal nodes' polygons as the case table does.
      {"OWNC", false, [this](LodModel&) { return array(packed_.own_cuts); }, kPacked},
    };
  }

  // The records as the writer of format `major` lays them out.
  void prepare(const LodModel& model, std::uint32_t major) override {
    const McOctree& t = model.octree->tree;
    if (major >= kPacked) packed_ = pack_octree(t);
    for (int i = 0; i < 3; ++i) std::memcpy(grid_ + 8 * i, &t.grid.origin[i], 8);
    std::memcpy(grid_ + 24, &t.grid.cube_size, 8);
    const std::int32_t resolution = t.grid.resolution, depth = t.depth;
    std::memcpy(grid_ + 32, &resolution, 4);
    std::memcpy(grid_ + 36, &depth, 4);
    put_u64(grid_ + 40, std::uint64_t(t.mesh_vertices));
    pinned_ = model.octree->lod.pinned;
  }

  // Format 2 held nothing else; from 3 on, the grid marks it.
  bool in(const SectionReader& file) const override { return file.major() == 2 || file.has("GRID"); }
  std::string mark() const override { return "an octree ('GRID')"; }

  void decode(SectionReader& file, LodModel* model) override {
    model->octree.emplace();
    McOctree& t = model->octree->tree;
    read_grid(file, &t);
    file.read_rows(rows(), model);
    if (file.major() >= kPacked) unpack_octree(packed_, file.source(), &t);
    read_pinned(file, &model->octree->lod);
    if (!file.has("STRF")) t.transitions.straight_faces.assign(t.transitions.size(), 0);
    check_octree_arrays(file, t);
    const std::size_t internal = check_nodes(file, t);
    check_transitions(file, t, internal);
    check_lod_array(file, t, model->octree->lod, internal);
  }

 private:
  static void read_grid(SectionReader& file, McOctree* t) {
    const FileSection& s = file.section("GRID");
    if (s.count != 1 || s.element_size < kGridRecordBytes)
      file.fail("section 'GRID' must be one record of at least " + std::to_string(kGridRecordBytes) + " bytes");
    const std::uint8_t* g = file.payload(s);
    for (int i = 0; i < 3; ++i) std::memcpy(&t->grid.origin[i], g + 8 * i, 8);
    std::memcpy(&t->grid.cube_size, g + 24, 8);
    std::int32_t resolution, depth;
    std::memcpy(&resolution, g + 32, 4);
    std::memcpy(&depth, g + 36, 4);
    t->grid.resolution = resolution;
    t->depth = depth;
    t->mesh_vertices = std::size_t(get_u64(g + 40));
  }

  // Optional (added in 1.1): without it nothing is pinned.
  static void read_pinned(SectionReader& file, LodArray* lod) {
    if (!file.has("PINC")) return;
    const FileSection& s = file.section("PINC");
    if (s.element_size != 8)
      file.fail("section 'PINC' has elements of " + bytes_text(s.element_size) + ", expected 8");
    if (s.count != 1) file.fail("section 'PINC' must hold one count, not " + std::to_string(s.count));
    lod->pinned = std::size_t(std::min<std::uint64_t>(get_u64(file.payload(s)), std::numeric_limits<std::size_t>::max()));
  }

  std::uint8_t grid_[kGridRecordBytes] = {};
  std::uint64_t pinned_ = 0;
  PackedOctree packed_;
};

void check_octree_arrays(const SectionReader& file, const McOctree& t) {
  // Contents: everything extraction indexes must be in range, and the tree a
  // tree, so that a crafted file cannot make it read out of bounds.
  const std::size_t n = t.nodes.keys.size(), vertices = file.vertices();
  if (n == 0) file.bad("the octree has no nodes");
  if (n > kMaxIndex) file.bad(std::to_string(n) + " nodes, more than 32-bit indices address");
  auto per_node = [&](const char* tag, std::size_t count) {
    if (count != n)
      file.bad("section '" + std::string(tag) + "' has " + std::to_string(count) + " entries for the " + std::to_string(n) +
          " nodes of 'KEYS'");
  };
  per_node("LEVL", t.nodes.levels.size());
  per_node("PRNT", t.nodes.parents.size());
  per_node("FCHD", t.nodes.first_child.size());
  per_node("NCHD", t.nodes.child_counts.size());
  per_node("CASE", t.nodes.cases.size());
  per_node("EDGV", t.nodes.edge_vertices.size());
  per_node("FTRI", t.nodes.first_triangle.size());
  per_node("NTRI", t.nodes.triangle_counts.size());
  per_node("METR", t.nodes.metrics.size());
  if (t.depth < 0 || t.depth > 19 || t.grid.resolution != (1 << t.depth))
    file.bad("resolution " + std::to_string(t.grid.resolution) + " is not 2^depth for depth " + std::to_string(t.depth));
  if (!t.grid.origin.allFinite() || !std::isfinite(t.grid.cube_size) || !(t.grid.cube_size > 0))
    file.bad("the grid's origin and cube size must be finite, the cube size positive");
  if (t.mesh_vertices > vertices)
    file.bad("mesh_vertices " + std::to_string(t.mesh_vertices) + " exceeds the " + std::to_string(vertices) + " vertices");
  if (t.triangles.size() > kMaxIndex) file.bad("more triangles than 32-bit indices address");
  auto check_triangles = [&](const char* tag, const auto& tris) {
    for (std::size_t i = 0; i < tris.size(); ++i)
      for (std::int32_t v : tris[i])
        if (v < 0 || std::size_t(v) >= vertices)
          file.bad("section '" + std::string(tag) + "': triangle " + std::to_string(i) + " names vertex " +
              std::to_string(v) + " of " + std::to_string(vertices));
  };
  check_triangles("TRIS", t.triangles);
  check_triangles("PTRI", t.patches.triangles);

  // Hole patches by group: offsets that run from 0 to the end of their array.
  auto check_offsets = [&](const char* tag, const auto& first, std::size_t total,
                           const char* of) {
    if (first.empty() ? total != 0 : first.front() != 0 || std::size_t(first.back()) != total ||
                                         !std::is_sorted(first.begin(), first.end()))
      file.bad("section '" + std::string(tag) + "' does not run from 0 to the " + std::to_string(total) + " entries of '" +
          of + "' in order");
  };
  if (t.patches.group_first.empty() && !t.patches.triangles.empty())
    file.bad("patch triangles without groups ('PGRP' is empty)");
  check_offsets("PGRP", t.patches.group_first, t.patches.triangles.size(), "PTRI");
  if (t.patches.needs_first.size() != t.patches.group_first.size())
    file.bad("section 'PNDF' has " + std::to_string(t.patches.needs_first.size()) + " entries, 'PGRP' " +
        std::to_string(t.patches.group_first.size()));
  check_offsets("PNDF", t.patches.needs_first, t.patches.needs.size(), "PNDS");
  for (std::int32_t v : t.patches.needs)
    if (v < 0 || std::size_t(v) >= n) file.bad("section 'PNDS' names node " + std::to_string(v) + " of " + std::to_string(n));

}

// The tree a tree, every index in range.
std::size_t check_nodes(const SectionReader& file, const McOctree& t) {
  const std::size_t n = t.nodes.keys.size(), vertices = file.vertices();
  if (t.nodes.parents[0] != -1 || t.nodes.levels[0] != 0 || t.nodes.keys[0] != 0) file.bad("node 0 is not the root");
  std::size_t internal = 0;
  for (std::size_t i = 0; i < n; ++i) {
    auto node = [i] { return "node " + std::to_string(i) + ": "; };  // built only on failure
    const int level = t.nodes.levels[i];
    if (level > t.depth) file.bad(node() + "level " + std::to_string(level) + " below the leaves' " + std::to_string(t.depth));
    if (t.nodes.keys[i] >> 60) file.bad(node() + "key out of range");
    int x, y, z;
    unpack_key(t.nodes.keys[i], &x, &y, &z);
    if (std::max({x, y, z}) >= (1 << level)) file.bad(node() + "key outside its level's lattice");
    if (i > 0) {
      const std::int32_t p = t.nodes.parents[i];
      if (p < 0 || std::size_t(p) >= n) file.bad(node() + "parent " + std::to_string(p) + " of " + std::to_string(n) + " nodes");
      if (t.nodes.first_child[p] < 0 || std::size_t(t.nodes.first_child[p]) > i ||
          i >= std::size_t(t.nodes.first_child[p]) + t.nodes.child_counts[p])
        file.bad(node() + "not among its parent " + std::to_string(p) + "'s children");
    }
    if (t.nodes.first_child[i] < 0) {
      if (t.nodes.child_counts[i] != 0 || level != t.depth) file.bad(node() + "a leaf must sit at the depth with no children");
    } else {
      ++internal;
      const std::size_t first = std::size_t(t.nodes.first_child[i]);
      if (t.nodes.child_counts[i] < 1 || t.nodes.child_counts[i] > 8 || first + t.nodes.child_counts[i] > n)
        file.bad(node() + "children " + std::to_string(first) + "+" + std::to_string(t.nodes.child_counts[i]) +
            " are not 1 to 8 of the " + std::to_string(n) + " nodes");
      for (std::size_t c = first; c < first + t.nodes.child_counts[i]; ++c) {
        int cx, cy, cz;
        unpack_key(t.nodes.keys[c], &cx, &cy, &cz);
        if (t.nodes.parents[c] != std::int32_t(i) || t.nodes.levels[c] != level + 1 || cx >> 1 != x || cy >> 1 != y ||
            cz >> 1 != z)
          file.bad(node() + "child " + std::to_string(c) + " does not lie inside it on the next level");
      }
    }
    if (t.nodes.first_triangle[i] < 0 ||
        std::size_t(t.nodes.first_triangle[i]) + t.nodes.triangle_counts[i] > t.triangles.size())
      file.bad(node() + "triangles " + std::to_string(t.nodes.first_triangle[i]) + "+" + std::to_string(t.nodes.triangle_counts[i]) +
          " past the " + std::to_string(t.triangles.size()) + " of 'TRIS'");
    for (std::int32_t v : t.nodes.edge_vertices[i])
      if (v < -1 || (v >= 0 && std::size_t(v) >= vertices))
        file.bad(node() + "edge vertex " + std::to_string(v) + " of " + std::to_string(vertices));
  }

  return internal;
}

void check_transitions(const SectionReader& file, const McOctree& t, std::size_t internal) {
  const std::size_t n = t.nodes.keys.size(), vertices = file.vertices();
  // Crack patching (lod/octree/transition.h): the internal nodes come first, and
  // every crossing the transition triangulation can join has a vertex.
  const std::size_t with_transitions = t.transitions.centre_vertices.size();
  if (with_transitions != internal)
    file.bad("section 'CNTR' has " + std::to_string(with_transitions) + " entries for the " + std::to_string(internal) +
        " internal nodes");
  auto per_internal = [&](const char* tag, std::size_t count) {
    if (count != internal)
      file.bad("section '" + std::string(tag) + "' has " + std::to_string(count) + " entries for the " +
          std::to_string(internal) + " internal nodes");
  };
  per_internal("BINS", t.transitions.boundary_inside.size());
  per_internal("SUBV", t.transitions.sub_edge_vertices.size());
  per_internal("NBRS", t.transitions.neighbours.size());
  per_internal("STRF", t.transitions.straight_faces.size());
  const auto& sub_edges = transition_sub_edges();
  auto vertex_ok = [&](std::int32_t v) { return v >= -1 && (v < 0 || std::size_t(v) < vertices); };
  int corner_point[8], edge_ends[12][2];
  for (int c = 0; c < 8; ++c) corner_point[c] = lattice_of_corner(c);
  for (int e = 0; e < 12; ++e)
    for (int end = 0; end < 2; ++end) edge_ends[e][end] = corner_point[edge_corner(e, end)];
  for (std::size_t i = 0; i < internal; ++i) {
    auto node = [i] { return "node " + std::to_string(i) + ": "; };  // built only on failure
    if (t.nodes.first_child[i] < 0) file.bad(node() + "a leaf among the first " + std::to_string(internal) + " nodes");
    const std::uint32_t inside = t.transitions.boundary_inside[i];
    if (inside >> 27) file.bad(node() + "boundary signs beyond the 27 lattice points");
    auto in = [&](int p) { return (inside >> p) & 1; };
    bool crossing = false;
    for (int c = 0; c < 8; ++c)
      if (std::uint32_t(in(corner_point[c])) != std::uint32_t((t.nodes.cases[i] >> c) & 1))
        file.bad(node() + "boundary signs disagree with its case at corner " + std::to_string(c));
    for (int e = 0; e < 12; ++e)
      if (in(edge_ends[e][0]) != in(edge_ends[e][1])) {
        crossing = true;
        if (t.nodes.edge_vertices[i][e] < 0) file.bad(node() + "edge " + std::to_string(e) + " changes sign without a vertex");
      }
    for (int e = 0; e < kSubEdges; ++e) {
      const std::int32_t v = t.transitions.sub_edge_vertices[i][e];
      if (!vertex_ok(v)) file.bad(node() + "sub-edge vertex " + std::to_string(v) + " of " + std::to_string(vertices));
      if (in(sub_edges[e].a) != in(sub_edges[e].b)) {
        crossing = true;
        if (v < 0) file.bad(node() + "sub-edge " + std::to_string(e) + " changes sign without a vertex");
      }
    }
    if (t.transitions.straight_faces[i] >> 6) file.bad(node() + "straight faces beyond the 6 faces");
    const std::int32_t centre = t.transitions.centre_vertices[i];
    if (!vertex_ok(centre) || (crossing && centre < 0))
      file.bad(node() + "centre vertex " + std::to_string(centre) + " of " + std::to_string(vertices));
    for (std::int32_t m : t.transitions.neighbours[i])
      if (m < -1 || (m >= 0 && std::size_t(m) >= n)) file.bad(node() + "neighbour " + std::to_string(m) + " of " + std::to_string(n));
  }

}

void check_lod_array(const SectionReader& file, const McOctree& t, const LodArray& lod, std::size_t internal) {
  const std::size_t n = t.nodes.keys.size();
  // The LOD array: every internal node once, parents first (§5.2).
  if (lod.order.size() != internal)
    file.bad("the LOD array has " + std::to_string(lod.order.size()) + " entries for " + std::to_string(internal) +
        " internal nodes");
  if (lod.accumulated.size() != internal + 1)
    file.bad("the accumulation table has " + std::to_string(lod.accumulated.size()) + " entries, expected " +
        std::to_string(internal + 1));
  std::vector<std::uint8_t> expanded(n, 0);
  for (std::size_t k = 0; k < lod.order.size(); ++k) {
    const std::int32_t v = lod.order[k];
    auto entry = [k] { return "LOD array entry " + std::to_string(k) + ": "; };
    if (v < 0 || std::size_t(v) >= n || t.nodes.first_child[v] < 0)
      file.bad(entry() + "node " + std::to_string(v) + " is not an internal node");
    if (expanded[v]) file.bad(entry() + "node " + std::to_string(v) + " expands twice");
    if (k == 0 ? v != 0 : !expanded[t.nodes.parents[v]]) file.bad(entry() + "node " + std::to_string(v) + " expands before its parent");
    expanded[v] = 1;
  }
  for (std::size_t k = 0; k < lod.accumulated.size(); ++k)
    if (lod.accumulated[k] < 0) file.bad("accumulation table entry " + std::to_string(k) + " is negative");
  if (lod.pinned > lod.order.size())
    file.bad(std::to_string(lod.pinned) + " pinned expansions of " + std::to_string(lod.order.size()));
  for (std::size_t k = 0; k < lod.inside_steps.size(); ++k)
    if (lod.inside_steps[k] < 0 || std::size_t(lod.inside_steps[k]) >= lod.order.size() ||
        (k > 0 && lod.inside_steps[k] <= lod.inside_steps[k - 1]))
      file.bad("entry " + std::to_string(k) + " of the priorities not offered ('STEP') is " +
          std::to_string(lod.inside_steps[k]) + ": expected ascending numbers below " + std::to_string(lod.order.size()));
}
}  // namespace

std::unique_ptr<StructureSections> octree_sections() { return std::make_unique<OctreeSections>(); }

}  // namespace scan2lod
