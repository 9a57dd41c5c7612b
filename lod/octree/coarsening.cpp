#include <scan2lod/lod/octree/coarsening.h>

#include <scan2lod/core/compact_mesh.h>
#include <scan2lod/lod/octree/extract.h>
#include <scan2lod/lod/octree/level_topology.h>
#include <scan2lod/reconstruct/cube_grid.h>

#include <algorithm>
#include <queue>

namespace scan2lod {
namespace {

// Up to this many triangles, an expansion the local checks refuse while the
// steps are replayed is counted whole (measure/topology.h): the local checks
// cannot tell a new rim that still leaves the level with no more loops than
// the full mesh, which an open scan's coarse levels need (bun000 at R = 256:
// 500 / 1000 / 2000 triangles got 451 / 451 / 451, now 497 / 997 / 1984).
constexpr std::int64_t kCountedWholeUpTo = 5000;

class Coarsening {
 public:
  Coarsening(const McOctree& tree, const std::vector<std::int32_t>& rank, const MeshTopology& full);
  CoarseningOrder run();

 private:
  void start();
  bool try_collapse(std::int32_t node);
  void gather_step(std::int32_t node, bool closed);
  bool neighbours_allow(std::int32_t node) const;
  void gather_change();
  void emit_change(bool expanded);
  void settle(std::int32_t node);  // collapsed or refused: its parent may be ready
  std::int32_t key(std::int32_t node) const;
  double added_triangles(std::int32_t node) const;
  template <class F>
  void for_each_needed(std::int32_t node, F f) const;
  bool may_expand(std::int32_t node) const;
  std::vector<std::int32_t> with_needs(std::int32_t node, const std::vector<std::int32_t>& remaining);
  std::vector<std::int32_t> grow_sound_set(const std::vector<std::int32_t>& remaining);
  void count_missing(const std::vector<std::int32_t>& nodes, int delta);
  bool try_expand(const std::vector<std::int32_t>& nodes, bool forced);
  void collapse(const std::vector<std::int32_t>& nodes);
  bool level_sound();
  void order_step(std::vector<std::int32_t> nodes, CoarseningOrder* out);
  CoarseningOrder replay();

  const McOctree& tree_;
  const std::vector<std::int32_t>& rank_;
  const MeshTopology& full_;
  LevelTopology topology_;

  std::vector<std::uint8_t> flags_;        // kExpanded (extract.h)
  std::vector<std::uint8_t> refused_;      // expanded for good, unless the parent takes it along
  std::vector<std::int32_t> pending_;      // children expanded and not refused
  std::vector<std::int32_t> missing_;      // per patch group: needs not expanded
  std::vector<std::int32_t> groups_first_, groups_;  // per node, the patch groups that need it
  std::priority_queue<std::pair<std::int32_t, std::int32_t>> queue_;  // (key, node)
  // Per node: the triangles that refused nodes under it add to its expansion.
  std::vector<double> carried_;
  // (metric, latest rank of a node with at least that metric), metric descending.
  std::vector<std::pair<float, std::int32_t>> rank_by_metric_;

  // The step being tried: its nodes, the cut nodes whose triangles it changes,
  // the patch groups it hides, and the triangles before and after.
  std::vector<std::int32_t> step_, changed_, hidden_;
  std::vector<std::uint8_t> mark_, in_step_, grown_;
  std::vector<Triangle> expanded_, collapsed_;

  std::vector<std::int32_t> step_nodes_, step_first_{0};  // accepted steps, in order
  std::int64_t triangles_ = 0;  // in the current level
  // For level_sound, scratch: a vertex's index in level_ (else -1), the
  // nodes to visit, the vertices given an index.
  std::vector<std::int32_t> compact_, visit_, compacted_;
  TriangleMesh level_;
};

Coarsening::Coarsening(const McOctree& tree, const std::vector<std::int32_t>& rank, const MeshTopology& full)
    : tree_(tree), rank_(rank), full_(full), topology_(tree.vertices.size(), tree.triangles.size()) {}

// The full mesh: every node above the leaves expanded, every patch shown.
void Coarsening::start() {
  const std::size_t n = tree_.size();
  flags_.assign(n, 0);
  refused_.assign(n, 0);
  pending_.assign(n, 0);
  mark_.assign(n, 0);
  in_step_.assign(n, 0);
  grown_.assign(n, 0);
  for (std::size_t node = 0; node < n; ++node) {
    if (tree_.is_leaf(node)) continue;
    flags_[node] = kExpanded;
    if (tree_.nodes.parents[node] >= 0) ++pending_[std::size_t(tree_.nodes.parents[node])];
  }
  carried_.assign(n, 0.0);
  for (std::size_t node = 0; node < n; ++node)
    if (!tree_.is_leaf(node) && tree_.nodes.metrics[node] > 0.f)
      rank_by_metric_.push_back({tree_.nodes.metrics[node], rank_[node]});
  std::sort(rank_by_metric_.begin(), rank_by_metric_.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (std::size_t i = 1; i < rank_by_metric_.size(); ++i)
    rank_by_metric_[i].second = std::max(rank_by_metric_[i].second, rank_by_metric_[i - 1].second);
  missing_.assign(tree_.patch_groups(), 0);
  groups_first_.assign(n + 1, 0);
  for (const std::int32_t node : tree_.patches.needs) ++groups_first_[std::size_t(node) + 1];
  for (std::size_t i = 0; i < n; ++i) groups_first_[i + 1] += groups_first_[i];
  groups_.resize(tree_.patches.needs.size());
  std::vector<std::int32_t> fill(groups_first_.begin(), groups_first_.end() - 1);
  for (std::size_t g = 0; g < tree_.patch_groups(); ++g)
    for (std::int32_t k = tree_.patches.needs_first[g]; k < tree_.patches.needs_first[g + 1]; ++k)
      groups_[std::size_t(fill[std::size_t(tree_.patches.needs[std::size_t(k)])]++)] = std::int32_t(g);

  const std::vector<Triangle> full = full_triangles(tree_);
  topology_.add(full);
  compact_.assign(tree_.vertices.size(), -1);
  triangles_ = std::int64_t(full.size());
  for (std::size_t node = 0; node < n; ++node)
    if (flags_[node] && pending_[node] == 0) queue_.push({rank_[node], std::int32_t(node)});
}

// The step that collapses `node`: it and the expanded nodes under it (all
// refused), parents first. `closed`: also what the neighbour rule then
// requires to collapse with them: expanded children of the nodes beside a
// collapsing node, with what is under them, until nothing more is needed.
void Coarsening::gather_step(std::int32_t node, bool closed) {
  step_.assign(1, node);
  in_step_[std::size_t(node)] = 1;
  auto take = [&](std::int32_t q) {
    if (in_step_[std::size_t(q)] || !(flags_[std::size_t(q)] & kExpanded)) return;
    in_step_[std::size_t(q)] = 1;
    step_.push_back(q);
  };
  for (std::size_t i = 0; i < step_.size(); ++i) {
    const std::int32_t s = step_[i];
    for (int c = 0; c < tree_.nodes.child_counts[s]; ++c) take(tree_.nodes.first_child[s] + c);
    if (!closed) continue;
    for (int c = 0; c < 27; ++c) {
      const std::int32_t q = tree_.transitions.neighbours[std::size_t(s)][std::size_t(c)];
      if (c == 13 || q < 0 || in_step_[std::size_t(q)] || !(flags_[std::size_t(q)] & kExpanded)) continue;
      for (int k = 0; k < tree_.nodes.child_counts[q]; ++k) take(tree_.nodes.first_child[q] + k);
    }
  }
  std::sort(step_.begin(), step_.end());
}

// Collapsed, `node` is a cut node on its level: the nodes of its level beside
// it must not have expanded children (they would be two levels finer).
bool Coarsening::neighbours_allow(std::int32_t node) const {
  const auto& around = tree_.transitions.neighbours[std::size_t(node)];
  for (int c = 0; c < 27; ++c) {
    const std::int32_t q = around[std::size_t(c)];
    if (c == 13 || q < 0 || !(flags_[std::size_t(q)] & kExpanded)) continue;
    for (int k = 0; k < tree_.nodes.child_counts[q]; ++k)
      if (flags_[std::size_t(tree_.nodes.first_child[q] + k)] & kExpanded) return false;
  }
  return true;
}

// The cut nodes the step re-emits: those under it, and those beside its nodes
// across a face or an edge (their transitions read its nodes' flags); and the
// patch groups it hides.
void Coarsening::gather_change() {
  changed_.clear();
  hidden_.clear();
  auto add = [&](std::int32_t q) {
    if (mark_[std::size_t(q)] & 2) return;
    mark_[std::size_t(q)] |= 2;
    changed_.push_back(q);
  };
  for (const std::int32_t s : step_) {
    for (int c = 0; c < tree_.nodes.child_counts[s]; ++c) {
      const std::int32_t child = tree_.nodes.first_child[s] + c;
      if (!(flags_[std::size_t(child)] & kExpanded)) add(child);
    }
    if (std::size_t(s) < tree_.internal_nodes())
      for (const int c : splitting_cells()) {
        const std::int32_t q = tree_.transitions.neighbours[std::size_t(s)][std::size_t(c)];
        if (q < 0 || (flags_[std::size_t(q)] & kExpanded)) continue;
        const std::int32_t up = tree_.nodes.parents[std::size_t(q)];
        if (up >= 0 && (flags_[std::size_t(up)] & kExpanded) && !in_step_[std::size_t(up)]) add(q);
      }
    for (std::int32_t k = groups_first_[std::size_t(s)]; k < groups_first_[std::size_t(s) + 1]; ++k) {
      const std::int32_t g = groups_[std::size_t(k)];
      if (missing_[std::size_t(g)] == 0 && std::find(hidden_.begin(), hidden_.end(), g) == hidden_.end())
        hidden_.push_back(g);
    }
  }
  for (const std::int32_t q : changed_) mark_[std::size_t(q)] = 0;
}

// The changed triangles with the step's nodes expanded or collapsed (the
// flags as they are now).
void Coarsening::emit_change(bool expanded) {
  std::vector<Triangle>& out = expanded ? expanded_ : collapsed_;
  out.clear();
  for (const std::int32_t q : changed_) {
    const std::int32_t up = tree_.nodes.parents[std::size_t(q)];
    // Under the step, only its top node stays in the cut.
    const bool under = up >= 0 && in_step_[std::size_t(up)];
    if (expanded || !under) emit_node(tree_, q, flags_, &out);
  }
  if (expanded) {
    for (const std::int32_t g : hidden_)
      out.insert(out.end(), tree_.patches.triangles.begin() + tree_.patches.group_first[std::size_t(g)],
                 tree_.patches.triangles.begin() + tree_.patches.group_first[std::size_t(g) + 1]);
  } else {
    for (const std::int32_t s : step_) {
      const std::int32_t up = tree_.nodes.parents[std::size_t(s)];
      if (up < 0 || !in_step_[std::size_t(up)]) emit_node(tree_, s, flags_, &out);
    }
  }
}

// Collapses `node` if the checks allow it: alone with what is under it where
// the neighbour rule allows that, else together with the finer neighbours the
// rule ties it to (at its own rank: left until nothing else could move, such
// steps let coarse nodes of far earlier rank, the bunny's head, collapse
// first, and its error at 10 k triangles was 2.3 times that of this order).
bool Coarsening::try_collapse(std::int32_t node) {
  gather_step(node, !neighbours_allow(node));
  gather_change();
  emit_change(true);
  for (const std::int32_t s : step_) flags_[std::size_t(s)] = 0;
  emit_change(false);
  const bool kept = topology_.keeps_topology(expanded_, collapsed_);
  if (kept) triangles_ += std::int64_t(collapsed_.size()) - std::int64_t(expanded_.size());
  if (!kept) {
    for (const std::int32_t s : step_) flags_[std::size_t(s)] = kExpanded;
  } else {
    topology_.commit();
    count_missing(step_, +1);
    step_nodes_.insert(step_nodes_.end(), step_.begin(), step_.end());
    step_first_.push_back(std::int32_t(step_nodes_.size()));
    // The step's other tops (taken for the neighbour rule) leave their parents' wait.
    for (const std::int32_t s : step_) {
      const std::int32_t up = tree_.nodes.parents[std::size_t(s)];
      if (s != node && up >= 0 && !in_step_[std::size_t(up)] && !refused_[std::size_t(s)]) settle(s);
    }
  }
  for (const std::int32_t s : step_) in_step_[std::size_t(s)] = 0;
  return kept;
}

void Coarsening::settle(std::int32_t node) {
  const std::int32_t up = tree_.nodes.parents[std::size_t(node)];
  if (up < 0) return;
  if (refused_[std::size_t(node)]) carried_[std::size_t(up)] += carried_[std::size_t(node)] + added_triangles(node);
  if (--pending_[std::size_t(up)] == 0) queue_.push({key(up), up});
}

// When `node` collapses: at its rank, unless refused nodes under it make its
// expansion dearer. Then it collapses where a node of its metric per triangle
// of the whole step would rank by metric, if that is later: the forward order
// takes it later, after cheaper expansions of the same worth. The refused
// nodes' triangles count a tenth. On the scanned bunny that took the error at
// 1k / 2k / 5k triangles from 5.65 / 3.49 / 1.76 to 4.68 / 2.86 / 1.49 (1e-3
// of the diagonal) at R = 256 and from 8.04 / 3.25 / 1.25 to 5.43 / 2.41 /
// 1.24 at R = 128; counted in full, or not at all, it lost at 1k on one or
// the other.
std::int32_t Coarsening::key(std::int32_t node) const {
  constexpr double kCarriedWeight = 0.1;
  const double carried = carried_[std::size_t(node)];
  if (carried <= 0.0) return rank_[std::size_t(node)];
  const double own = added_triangles(node);
  const float metric = float(tree_.nodes.metrics[std::size_t(node)] * own / (own + kCarriedWeight * carried));
  const auto after = std::partition_point(rank_by_metric_.begin(), rank_by_metric_.end(),
                                          [&](const auto& e) { return e.first > metric; });
  if (after == rank_by_metric_.begin()) return rank_[std::size_t(node)];
  return std::max(rank_[std::size_t(node)], std::prev(after)->second);
}

// The triangles `node`'s expansion adds: its children's less its own, at least 1.
double Coarsening::added_triangles(std::int32_t node) const {
  return double(std::max(1, tree_.children_triangles(std::size_t(node)) - int(tree_.nodes.triangle_counts[std::size_t(node)])));
}

CoarseningOrder Coarsening::run() {
  start();
  while (!queue_.empty()) {
    const std::int32_t node = queue_.top().second;
    queue_.pop();
    if (!(flags_[std::size_t(node)] & kExpanded) || refused_[std::size_t(node)] || pending_[std::size_t(node)] != 0) continue;
    if (!try_collapse(node)) refused_[std::size_t(node)] = 1;
    settle(node);
  }
  return replay();
}

// Calls `f` on what must expand before `node` may: its parent, and the node
// above each of its 26 neighbour cells one level up (Lee's neighbour rule),
// where they have not; stops when `f` returns false.
template <class F>
void Coarsening::for_each_needed(std::int32_t node, F f) const {
  const std::int32_t up = tree_.nodes.parents[std::size_t(node)];
  if (up < 0) return;
  if (!(flags_[std::size_t(up)] & kExpanded) && !f(up)) return;
  int x, y, z;
  unpack_key(tree_.nodes.keys[std::size_t(node)], &x, &y, &z);
  const auto& around = tree_.transitions.neighbours[std::size_t(up)];
  for (int c = 0; c < 27; ++c) {
    const int cell = (((x + c % 3 - 1) >> 1) - (x >> 1) + 1) + 3 * (((y + c / 3 % 3 - 1) >> 1) - (y >> 1) + 1) +
                     9 * (((z + c / 9 - 1) >> 1) - (z >> 1) + 1);
    const std::int32_t q = around[std::size_t(cell)];
    if (q >= 0 && q != up && !tree_.is_leaf(std::size_t(q)) && !(flags_[std::size_t(q)] & kExpanded) && !f(q)) return;
  }
}

bool Coarsening::may_expand(std::int32_t node) const {
  bool may = true;
  for_each_needed(node, [&](std::int32_t) { return may = false; });
  return may;
}

// `node` with all it needs, recursively, each before what needs it (they are
// a level coarser), all among the `remaining` nodes of the step; empty if
// something needed is not among them.
std::vector<std::int32_t> Coarsening::with_needs(std::int32_t node, const std::vector<std::int32_t>& remaining) {
  for (const std::int32_t q : remaining) mark_[std::size_t(q)] = 4;
  std::vector<std::int32_t> set{node};
  mark_[std::size_t(node)] = 8;
  bool complete = true;
  for (std::size_t i = 0; i < set.size() && complete; ++i)
    for_each_needed(set[i], [&](std::int32_t q) {
      if (mark_[std::size_t(q)] == 4) {
        mark_[std::size_t(q)] = 8;
        set.push_back(q);
      }
      return complete = mark_[std::size_t(q)] == 8;
    });
  for (const std::int32_t q : remaining) mark_[std::size_t(q)] = 0;
  if (!complete) return {};
  std::sort(set.begin(), set.end(), [&](std::int32_t a, std::int32_t b) {
    return tree_.nodes.levels[std::size_t(a)] < tree_.nodes.levels[std::size_t(b)];
  });
  return set;
}

// Whether the current level (flags_, missing_) is sound, counted whole over
// its own vertices.
bool Coarsening::level_sound() {
  level_.triangles.clear();
  visit_.assign(1, 0);
  while (!visit_.empty()) {
    const std::int32_t q = visit_.back();
    visit_.pop_back();
    if (flags_[std::size_t(q)] & kExpanded) {
      for (int c = 0; c < tree_.nodes.child_counts[q]; ++c) visit_.push_back(tree_.nodes.first_child[q] + c);
    } else {
      emit_node(tree_, q, flags_, &level_.triangles);
    }
  }
  for (std::size_t g = 0; g < tree_.patch_groups(); ++g)
    if (missing_[g] == 0)
      level_.triangles.insert(level_.triangles.end(), tree_.patches.triangles.begin() + tree_.patches.group_first[g],
                              tree_.patches.triangles.begin() + tree_.patches.group_first[g + 1]);
  compacted_.clear();
  renumber_used(&level_.triangles, &compact_, &compacted_);
  level_.positions.clear();
  for (const std::int32_t v : compacted_) {
    level_.positions.push_back(tree_.vertices.positions[std::size_t(v)]);
    compact_[std::size_t(v)] = -1;
  }
  return sound_level(mesh_topology(level_), full_);
}

// The patch groups that need `nodes` miss `delta` more of them each.
void Coarsening::count_missing(const std::vector<std::int32_t>& nodes, int delta) {
  for (const std::int32_t node : nodes)
    for (std::int32_t k = groups_first_[std::size_t(node)]; k < groups_first_[std::size_t(node) + 1]; ++k)
      missing_[std::size_t(groups_[std::size_t(k)])] += delta;
}

// Expands `nodes` together if that keeps the level sound, or anyway when
// `forced`.
bool Coarsening::try_expand(const std::vector<std::int32_t>& nodes, bool forced) {
  auto set_flags = [&](std::uint8_t f) {
    for (const std::int32_t node : nodes) flags_[std::size_t(node)] = f;
  };
  set_flags(kExpanded);
  count_missing(nodes, -1);
  step_ = nodes;
  for (const std::int32_t node : nodes) in_step_[std::size_t(node)] = 1;
  gather_change();
  emit_change(true);
  set_flags(0);
  emit_change(false);
  const bool checked = !forced && topology_.keeps_topology(collapsed_, expanded_);
  bool kept = forced || checked;
  if (!kept && triangles_ - std::int64_t(collapsed_.size()) + std::int64_t(expanded_.size()) <= kCountedWholeUpTo) {
    set_flags(kExpanded);
    kept = level_sound();
    set_flags(0);
  }
  if (kept) {
    set_flags(kExpanded);
    if (checked)
      topology_.commit();
    else
      topology_.replace(collapsed_, expanded_);
    triangles_ += std::int64_t(expanded_.size()) - std::int64_t(collapsed_.size());
  } else {
    count_missing(nodes, +1);
  }
  for (const std::int32_t node : nodes) in_step_[std::size_t(node)] = 0;
  return kept;
}

// Collapses `nodes` unchecked: all expanded, each one's parent among them
// but the root's.
void Coarsening::collapse(const std::vector<std::int32_t>& nodes) {
  step_ = nodes;
  for (const std::int32_t node : nodes) in_step_[std::size_t(node)] = 1;
  gather_change();
  emit_change(true);
  for (const std::int32_t node : nodes) flags_[std::size_t(node)] = 0;
  count_missing(nodes, +1);
  emit_change(false);
  topology_.replace(expanded_, collapsed_);
  triangles_ += std::int64_t(collapsed_.size()) - std::int64_t(expanded_.size());
  for (const std::int32_t node : nodes) in_step_[std::size_t(node)] = 0;
}

// A set of the step's `remaining` nodes whose expansion together keeps the
// level sound, with all they need, short of the whole; empty if none is
// found. Grown one node (with what it needs) at a time, the deepest first: a
// thin part's deepest nodes with their needs may still float free (the
// bunny's ear), and the coarser nodes around them join them to the rest.
std::vector<std::int32_t> Coarsening::grow_sound_set(const std::vector<std::int32_t>& remaining) {
  std::vector<std::int32_t> seeds = remaining, set;
  auto deeper = [&](std::int32_t a, std::int32_t b) {
    return tree_.nodes.levels[std::size_t(a)] > tree_.nodes.levels[std::size_t(b)];
  };
  std::stable_sort(seeds.begin(), seeds.end(), deeper);
  bool found = false;
  for (const std::int32_t seed : seeds) {
    if (grown_[std::size_t(seed)]) continue;
    for (const std::int32_t q : with_needs(seed, remaining))
      if (!grown_[std::size_t(q)]) {
        grown_[std::size_t(q)] = 1;
        set.push_back(q);
      }
    if (set.size() == remaining.size()) break;
    std::stable_sort(set.begin(), set.end(), [&](std::int32_t a, std::int32_t b) { return deeper(b, a); });
    if ((found = try_expand(set, false))) break;
  }
  for (const std::int32_t q : remaining) grown_[std::size_t(q)] = 0;
  if (!found) set.clear();
  return set;
}

// The nodes of one step in an order whose prefixes stay sound as long as
// they can. Each time: the first node by rank that may expand and whose
// expansion keeps the level sound; else the first whose expansion together
// with all it needs does; else a set grown from the deepest nodes
// (grow_sound_set); else the first node that may expand, after which the
// rest of the step's prefixes are not offered.
void Coarsening::order_step(std::vector<std::int32_t> nodes, CoarseningOrder* out) {
  std::sort(nodes.begin(), nodes.end(),
            [&](std::int32_t a, std::int32_t b) { return rank_[std::size_t(a)] < rank_[std::size_t(b)]; });
  bool sound = true;
  auto take = [&](const std::vector<std::int32_t>& set) {
    for (const std::int32_t node : set) {
      out->order.push_back(node);
      nodes.erase(std::find(nodes.begin(), nodes.end(), node));
      if (node != set.back() || (!sound && !nodes.empty()))
        out->inside_steps.push_back(std::int32_t(out->order.size()));
    }
  };
  while (!nodes.empty()) {
    std::vector<std::int32_t> chosen;
    if (sound)
      for (const std::int32_t node : nodes)
        if (may_expand(node) && try_expand({node}, false)) {
          chosen.assign(1, node);
          break;
        }
    if (sound && chosen.empty())
      for (const std::int32_t node : nodes) {
        if (may_expand(node)) continue;
        std::vector<std::int32_t> set = with_needs(node, nodes);
        if (!set.empty() && try_expand(set, false)) {
          chosen = std::move(set);
          break;
        }
      }
    if (sound && chosen.empty()) chosen = grow_sound_set(nodes);
    if (chosen.empty()) {
      for (const std::int32_t node : nodes)
        if (may_expand(node)) {
          chosen.assign(1, node);
          break;
        }
      if (chosen.empty()) chosen.assign(1, nodes.front());  // cannot happen: a balanced step's parents come first
      try_expand(chosen, true);
      sound = false;
    }
    take(chosen);
  }
}

// The steps reversed: first what stayed expanded (the coarsest level's
// nodes), then each step's nodes, replayed from the coarsest level on so
// that, while levels are small, a step's nodes come in an order that keeps as
// many of its prefixes sound as it can.
CoarseningOrder Coarsening::replay() {
  constexpr std::int64_t kReorderedUpTo = 25000;  // triangles
  CoarseningOrder out;
  std::vector<std::int32_t> coarsest;
  for (std::size_t node = 0; node < tree_.size(); ++node)
    if (flags_[node] & kExpanded) coarsest.push_back(std::int32_t(node));
  out.coarsest = coarsest.size();
  if (triangles_ <= kReorderedUpTo && coarsest.size() > 1) {
    // From the root's level, which the checks have not seen: its prefixes are
    // all counted whole (lod/octree/octree_order.cpp), none offered here.
    collapse(coarsest);
    CoarseningOrder chunk;
    order_step(std::move(coarsest), &chunk);
    out.order = std::move(chunk.order);
  } else {
    out.order = std::move(coarsest);
  }
  for (std::int32_t p = 0; p < std::int32_t(out.coarsest); ++p) out.inside_steps.push_back(p);
  for (std::size_t s = step_first_.size() - 1; s-- > 0;) {
    const std::int32_t first = std::int32_t(out.order.size());
    std::vector<std::int32_t> nodes(step_nodes_.begin() + step_first_[s], step_nodes_.begin() + step_first_[s + 1]);
    if (triangles_ > kReorderedUpTo) {
      out.order.insert(out.order.end(), nodes.begin(), nodes.end());
      for (std::int32_t p = first + 1; p < std::int32_t(out.order.size()); ++p) out.inside_steps.push_back(p);
    } else if (nodes.size() == 1) {
      try_expand({nodes.front()}, true);
      out.order.push_back(nodes.front());
    } else {
      order_step(std::move(nodes), &out);
    }
  }
  return out;
}

}  // namespace

CoarseningOrder coarsen(const McOctree& tree, const std::vector<std::int32_t>& rank, const MeshTopology& full) {
  return Coarsening(tree, rank, full).run();
}

}  // namespace scan2lod
