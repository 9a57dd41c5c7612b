#include <scan2lod/delivery/tile_tree.h>

#include <scan2lod/core/error.h>
#include <scan2lod/core/flat_hash.h>
#include <scan2lod/delivery/cluster_geometry.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace scan2lod {
namespace {

// What the planner reads of each cluster, gathered once.
struct ClusterFacts {
  float own = kFullDetail;                                // own group's error; kFullDetail at full detail
  float parent = std::numeric_limits<float>::infinity();  // parent group's; infinite at the top
  Aabb box;
};

struct Planner {
  Planner(const LodModel& model, const TileOptions& options, const TileContentSink& sink)
      : h(&*model.clusters), options(&options), sink(&sink), geometry(model) {}
  const ClusterHierarchy* h;
  const TileOptions* options;
  const TileContentSink* sink;
  ClusterGeometry geometry;
  std::vector<ClusterFacts> facts;
  std::vector<float> thresholds;  // kFullDetail, then the distinct group errors rising
  TileTree tree;
  std::int64_t placed = 0;
  // The tile being filled: its content, and the model's vertex -> its own.
  TileContent content;
  FlatHashMap tile_vertices{1024};
};

bool overlaps(const Aabb& a, const Aabb& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

bool inside(const Aabb& a, const Aabb& cell) {
  return (cell.min.array() <= a.min.array()).all() && (a.max.array() <= cell.max.array()).all();
}

Aabb triangle_box(const ClusterTriangles& ct, const Triangle& t) {
  Aabb box;
  for (std::int32_t v : t) box.extend(ct.positions[v]);
  return box;
}

bool drawn_at(const ClusterFacts& f, float threshold) { return f.own <= threshold && !(f.parent <= threshold); }

void gather_facts(Planner& p) {
  const ClusterHierarchy& h = *p.h;
  p.facts.resize(h.clusters.size());
  std::vector<float> errors;
  for (const GroupBound& g : h.groups) errors.push_back(g.error);
  std::sort(errors.begin(), errors.end());
  errors.erase(std::unique(errors.begin(), errors.end()), errors.end());
  p.thresholds.push_back(kFullDetail);
  for (float e : errors)
    if (e > kFullDetail) p.thresholds.push_back(e);
  for (std::size_t c = 0; c < h.clusters.size(); ++c) {
    const Cluster& cl = h.clusters[c];
    ClusterFacts& f = p.facts[c];
    // An error of exactly kFullDetail cannot occur (errors are >= 0), so a
    // level-0 cluster is drawn at kFullDetail and nothing else is.
    if (cl.own_group >= 0) f.own = std::max(0.f, h.groups[std::size_t(cl.own_group)].error);
    if (cl.parent_group >= 0) f.parent = std::max(0.f, h.groups[std::size_t(cl.parent_group)].error);
    const ClusterTriangles ct = p.geometry.triangles(std::int32_t(c));
    for (std::size_t t = 0; t < ct.count; ++t)
      for (std::int32_t v : ct.triangles[t]) f.box.extend(ct.positions[v]);
    p.tree.bounds.extend(f.box.min);
    p.tree.bounds.extend(f.box.max);
  }
  p.tree.coarsest_error = p.thresholds.back() == kFullDetail ? 0.f : p.thresholds.back();
  p.tree.full_triangles = h.full_triangles;
}

// Triangles of cluster `c` that touch `cell`.
std::int32_t touching_cell(Planner& p, std::int32_t c, const Aabb& cell) {
  if (inside(p.facts[std::size_t(c)].box, cell)) return p.h->clusters[std::size_t(c)].triangle_count;
  const ClusterTriangles ct = p.geometry.triangles(c);
  std::int32_t n = 0;
  for (std::size_t t = 0; t < ct.count; ++t) n += overlaps(triangle_box(ct, ct.triangles[t]), cell);
  return n;
}

// Triangles of the cut at `threshold` that touch `cell`, among `candidates`.
// touching[i] is candidates[i]'s touching_cell, counted when first asked
// (-1 before): the search for a cell's cut asks at several thresholds, and a
// cluster's triangles, perhaps a page read from disk, are read once.
std::int64_t count_in_cell(Planner& p, const std::vector<std::int32_t>& candidates, float threshold,
                           const Aabb& cell, std::vector<std::int32_t>* touching) {
  std::int64_t n = 0;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (!drawn_at(p.facts[std::size_t(candidates[i])], threshold)) continue;
    std::int32_t& count = (*touching)[i];
    if (count < 0) count = touching_cell(p, candidates[i], cell);
    n += count;
  }
  return n;
}

// The finest threshold index below `above` whose cut fits the budget in
// `cell`, or `above` when none does. Finer cuts hold more triangles nearly
// always (a coarse triangle may touch a cell its finer ones miss), so a
// binary search finds it.
std::size_t finest_fitting(Planner& p, const std::vector<std::int32_t>& candidates, std::size_t above,
                           const Aabb& cell) {
  const std::int64_t budget = p.options->max_triangles;
  if (above == 0) return 0;
  std::vector<std::int32_t> touching(candidates.size(), -1);
  if (count_in_cell(p, candidates, p.thresholds[above - 1], cell, &touching) > budget) return above;
  std::size_t lo = 0, hi = above - 1;  // hi fits
  while (lo < hi) {
    const std::size_t mid = (lo + hi) / 2;
    if (count_in_cell(p, candidates, p.thresholds[mid], cell, &touching) <= budget) hi = mid;
    else lo = mid + 1;
  }
  return hi;
}

// Vertex `i` of `ct` as the tile's own, added the first time the tile uses it.
std::int32_t tile_vertex(Planner& p, Tile& tile, const ClusterTriangles& ct, std::int32_t i) {
  TileContent& out = p.content;
  const std::uint32_t model_vertex = ct.model_vertex(i);
  const std::int32_t next = std::int32_t(out.model_vertices.size());
  const std::int32_t id = p.tile_vertices.insert(model_vertex, next);
  if (id != next) return id;
  out.model_vertices.push_back(model_vertex);
  out.vertices.positions.push_back(ct.positions[i]);
  if (ct.normals) out.vertices.normals.push_back(ct.normals[i]);
  if (ct.colors) out.vertices.colors.push_back(ct.colors[i]);
  tile.content_box.extend(ct.positions[i]);
  return id;
}

// Fills `tile`'s content (into p.content): the cut at its threshold,
// triangles touching its cell.
void take_content(Planner& p, Tile& tile, const std::vector<std::int32_t>& candidates) {
  TileContent& out = p.content;
  out.vertices.positions.clear();
  out.vertices.normals.clear();
  out.vertices.colors.clear();
  out.triangles.clear();
  out.model_vertices.clear();
  p.tile_vertices.clear();
  for (std::int32_t c : candidates) {
    const ClusterFacts& f = p.facts[std::size_t(c)];
    if (!drawn_at(f, tile.threshold)) continue;
    const bool whole = inside(f.box, tile.cell);
    const std::size_t before = out.triangles.size();
    const ClusterTriangles ct = p.geometry.triangles(c);
    for (std::size_t t = 0; t < ct.count; ++t) {
      const Triangle& tri = ct.triangles[t];
      if (!whole && !overlaps(triangle_box(ct, tri), tile.cell)) continue;
      out.triangles.push_back({tile_vertex(p, tile, ct, tri[0]), tile_vertex(p, tile, ct, tri[1]),
                               tile_vertex(p, tile, ct, tri[2])});
    }
    if (out.triangles.size() == before) continue;
    tile.content_error = std::max(tile.content_error, std::max(0.f, f.own));
  }
  tile.triangle_count = std::int64_t(out.triangles.size());
  if (tile.threshold == kFullDetail) p.placed += tile.triangle_count;
}

// Hands tiles[index]'s content out, once the tile is in the tree.
void deliver(const Planner& p, std::size_t index) {
  if (*p.sink && p.tree.tiles[index].has_content()) (*p.sink)(p.tree, index, p.content);
}

Aabb octant(const Aabb& cell, int o) {
  const Vec3f mid = (cell.min + cell.max) * 0.5f;
  Aabb out;
  for (int k = 0; k < 3; ++k) {
    const bool high = (o >> k) & 1;
    out.min[k] = high ? mid[k] : cell.min[k];
    out.max[k] = high ? cell.max[k] : mid[k];
  }
  return out;
}

// The clusters of `candidates` that a cut finer than thresholds[above] may
// draw inside `cell`.
std::vector<std::int32_t> candidates_below(const Planner& p, const std::vector<std::int32_t>& candidates,
                                           std::size_t above, const Aabb& cell) {
  std::vector<std::int32_t> out;
  const float limit = p.thresholds[above];
  for (std::int32_t c : candidates) {
    const ClusterFacts& f = p.facts[std::size_t(c)];
    if (f.own < limit && overlaps(f.box, cell)) out.push_back(c);
  }
  return out;
}

void report_progress(const Planner& p) {
  if (p.options->progress && p.h->full_triangles > 0)
    p.options->progress(std::min(1.0, double(p.placed) / double(p.h->full_triangles)));
}

// Makes the children of tiles[index], whose cut is thresholds[level], and
// recurses into them.
void split(Planner& p, int index, std::size_t level, const std::vector<std::int32_t>& candidates) {
  if (level == 0) return;  // full detail
  for (int o = 0; o < 8; ++o) {
    const Aabb cell = octant(p.tree.tiles[std::size_t(index)].cell, o);
    std::vector<std::int32_t> mine = candidates_below(p, candidates, level, cell);
    if (mine.empty()) continue;
    Tile child;
    child.parent = index;
    child.depth = p.tree.tiles[std::size_t(index)].depth + 1;
    child.name = p.tree.tiles[std::size_t(index)].name + char('0' + o);
    child.cell = cell;
    std::size_t child_level = finest_fitting(p, mine, level, cell);
    if (child_level == level && child.depth >= p.options->max_depth) child_level = level - 1;
    child.threshold = p.thresholds[child_level];
    if (child_level < level) take_content(p, child, mine);
    // Clusters whose boxes meet the cell while none of their full-detail
    // triangles do: nothing to draw and nothing below.
    if (child_level == 0 && !child.has_content()) continue;
    const int child_index = int(p.tree.tiles.size());
    p.tree.tiles.push_back(std::move(child));
    p.tree.tiles[std::size_t(index)].children.push_back(child_index);
    deliver(p, std::size_t(child_index));
    report_progress(p);
    split(p, child_index, child_level, mine);
  }
}

// Errors never grow going down, and boxes enclose the boxes below: children
// come after their parents, so one pass backwards settles both.
void settle_errors_and_boxes(TileTree& tree) {
  for (Tile& t : tree.tiles) {
    t.geometric_error = t.content_error;
    t.subtree_box = t.content_box;
  }
  for (std::size_t i = tree.tiles.size(); i-- > 1;) {
    const Tile& t = tree.tiles[i];
    Tile& parent = tree.tiles[std::size_t(t.parent)];
    parent.geometric_error = std::max(parent.geometric_error, t.geometric_error);
    if (!t.subtree_box.empty()) {
      parent.subtree_box.extend(t.subtree_box.min);
      parent.subtree_box.extend(t.subtree_box.max);
    }
  }
}

// A tile with no content stands for its parent's cut until its children
// load: give it its parent's error, so that a viewer refines through it at
// once.
void settle_empty_tiles(TileTree& tree) {
  for (std::size_t i = 1; i < tree.tiles.size(); ++i)
    if (!tree.tiles[i].has_content() && !tree.tiles[i].leaf())
      tree.tiles[i].geometric_error = tree.tiles[std::size_t(tree.tiles[i].parent)].geometric_error;
}

}  // namespace

TileTree plan_tiles(const LodModel& model, const TileOptions& options, const std::string& source,
                    const TileContentSink& content) {
  require_structure(model, LodStructure::kClusters, source);
  if (options.max_triangles < 1) throw InputError(source, "a tile must hold at least one triangle");
  if (model.clusters->clusters.empty()) throw InputError(source, "the cluster hierarchy has no clusters");
  if (model.clusters->spool)
    throw InputError(source, "the cluster hierarchy's triangles are still spooled; save the model first");
  Planner p(model, options, content);
  gather_facts(p);
  // A cubic root cell, so that octants stay cubes and a cell's size says its depth.
  Aabb cell = p.tree.bounds;
  const Vec3f centre = (cell.min + cell.max) * 0.5f;
  const float half = 0.5f * cell.extent().maxCoeff() * (1 + 1e-5f) + 1e-30f;
  cell.min = centre - Vec3f::Constant(half);
  cell.max = centre + Vec3f::Constant(half);

  std::vector<std::int32_t> all(p.h->clusters.size());
  for (std::size_t c = 0; c < all.size(); ++c) all[c] = std::int32_t(c);
  Tile root;
  root.name = "r";
  root.cell = cell;
  const std::size_t top = p.thresholds.size() - 1;
  root.threshold = p.thresholds[top];
  take_content(p, root, all);
  p.tree.tiles.push_back(std::move(root));
  deliver(p, 0);
  split(p, 0, top, all);
  settle_errors_and_boxes(p.tree);
  settle_empty_tiles(p.tree);
  if (options.progress) options.progress(1.0);
  return std::move(p.tree);
}

}  // namespace scan2lod
