#include <scan2lod/lod/octree/level_topology.h>

#include <algorithm>

namespace scan2lod {
namespace {

constexpr std::uint64_t kEmpty = ~0ull;  // no edge: vertex ids are below 2^31

std::size_t hash_edge(std::uint64_t key, std::size_t mask) {
  return std::size_t((key * 0x9E3779B97F4A7C15ull) >> 20) & mask;
}

std::int32_t find(std::vector<std::int32_t>& parent, std::int32_t i) {
  while (parent[std::size_t(i)] != i) i = parent[std::size_t(i)] = parent[std::size_t(parent[std::size_t(i)])];
  return i;
}

void unite(std::vector<std::int32_t>& parent, std::int32_t a, std::int32_t b) {
  a = find(parent, a), b = find(parent, b);
  if (a != b) parent[std::size_t(std::max(a, b))] = std::min(a, b);
}

}  // namespace

LevelTopology::LevelTopology(std::size_t vertices, std::size_t edges)
    : uses_(vertices, 0), boundary_degree_(vertices, 0), local_(vertices, -1) {
  std::size_t capacity = 1024;
  while (capacity < 2 * edges) capacity *= 2;
  table_.assign(capacity, Slot{kEmpty, 0, -1});
}

// Room for `more` new edges at under half load, so that slots stay put
// while a change is checked and committed.
void LevelTopology::reserve(std::size_t more) {
  if (2 * (used_ + more) <= table_.size()) return;
  std::size_t capacity = table_.size();
  while (2 * (used_ + more) > capacity) capacity *= 2;
  // Rebuilt without the edges no triangle uses any more.
  std::vector<Slot> old(capacity, Slot{kEmpty, 0, -1});
  old.swap(table_);
  used_ = 0;
  const std::size_t mask = table_.size() - 1;
  for (const Slot& s : old) {
    if (s.key == kEmpty || s.count == 0) continue;
    std::size_t i = hash_edge(s.key, mask);
    while (table_[i].key != kEmpty) i = (i + 1) & mask;
    table_[i] = s;
    ++used_;
  }
}

std::size_t LevelTopology::slot_of(std::uint64_t key) {
  const std::size_t mask = table_.size() - 1;
  for (std::size_t i = hash_edge(key, mask);; i = (i + 1) & mask) {
    if (table_[i].key == key) return i;
    if (table_[i].key == kEmpty) {
      ++used_;
      table_[i] = Slot{key, 0, -1};
      return i;
    }
  }
}

void LevelTopology::change_edge(std::size_t slot, int delta) {
  Slot& s = table_[slot];
  const bool was = s.count == 1;
  s.count += delta;
  if (was != (s.count == 1)) {
    const int step = was ? -1 : 1;
    boundary_degree_[std::size_t(s.key >> 32)] += step;
    boundary_degree_[std::size_t(s.key & 0xffffffffu)] += step;
  }
}

void LevelTopology::add(const std::vector<Triangle>& triangles) {
  for (const Triangle& t : triangles)
    for (int k = 0; k < 3; ++k) {
      reserve(1);
      ++uses_[std::size_t(t[k])];
      change_edge(slot_of(edge_key(t[k], t[(k + 1) % 3])), +1);
    }
}

void LevelTopology::gather(const std::vector<Triangle>& removed, const std::vector<Triangle>& added) {
  vertex_of_.clear();
  locals_.clear();
  edges_.clear();
  reserve(3 * (removed.size() + added.size()));
  for (int side = 0; side < 2; ++side)
    for (const Triangle& t : side ? added : removed)
      for (int k = 0; k < 3; ++k) {
        std::int32_t& id = local_[std::size_t(t[k])];
        if (id < 0) {
          id = std::int32_t(vertex_of_.size());
          vertex_of_.push_back(t[k]);
          locals_.push_back(Local{0, 0, {0, 0}, 0});
        }
        Local& l = locals_[std::size_t(id)];
        (side ? l.added_uses : l.removed_uses) += 1;
        const std::size_t slot = slot_of(edge_key(t[k], t[(k + 1) % 3]));
        if (table_[slot].local < 0) {
          table_[slot].local = std::int32_t(edges_.size());
          edges_.push_back(EdgeUse{slot, 0, 0, table_[slot].count});
        }
        EdgeUse& e = edges_[std::size_t(table_[slot].local)];
        (side ? e.added : e.removed) += 1;
      }
}

void LevelTopology::release() {
  for (const std::int32_t v : vertex_of_) local_[std::size_t(v)] = -1;
  for (const EdgeUse& e : edges_) table_[e.slot].local = -1;
}

// Boundary loops are the boundary edges' connected components. Rims that
// reach the rest of the level (through a port: a vertex with boundary edges
// outside the change) must stay joined as they were, and the rims wholly
// inside the change must not grow in number.
bool LevelTopology::boundary_kept() {
  const std::size_t n = locals_.size();
  for (int side = 0; side < 2; ++side) {
    parent_[side].resize(n);
    for (std::size_t i = 0; i < n; ++i) parent_[side][i] = std::int32_t(i);
  }
  for (const EdgeUse& e : edges_) {
    const std::int32_t before = e.before, after = before - e.removed + e.added;
    if (after > 2 && after > before) return false;  // a new non-manifold edge
    const std::uint64_t key = table_[e.slot].key;
    const std::int32_t a = local_[std::size_t(key >> 32)], b = local_[std::size_t(key & 0xffffffffu)];
    for (int side = 0; side < 2; ++side)
      if ((side ? after : before) == 1) {
        ++locals_[std::size_t(a)].rims[side], ++locals_[std::size_t(b)].rims[side];
        unite(parent_[side], a, b);
      }
  }
  for (std::size_t i = 0; i < n; ++i)
    locals_[i].outside = boundary_degree_[std::size_t(vertex_of_[i])] - locals_[i].rims[0];
  // Per side and root: a port of the piece (-1: none, a loop inside).
  int inside[2] = {0, 0};
  for (int side = 0; side < 2; ++side) {
    partner_[side].assign(n, -1);
    for (std::size_t i = 0; i < n; ++i)
      if (locals_[i].rims[side] > 0 && locals_[i].outside > 0) partner_[side][std::size_t(find(parent_[side], std::int32_t(i)))] = std::int32_t(i);
    for (std::size_t i = 0; i < n; ++i)
      if (locals_[i].rims[side] > 0 && find(parent_[side], std::int32_t(i)) == std::int32_t(i) && partner_[side][i] < 0) ++inside[side];
  }
  if (inside[1] > inside[0]) return false;
  for (std::size_t i = 0; i < n; ++i) {
    if (locals_[i].rims[0] == 0 || locals_[i].outside == 0) continue;
    const std::int32_t other = partner_[0][std::size_t(find(parent_[0], std::int32_t(i)))];
    if (other == std::int32_t(i)) continue;
    if (locals_[i].rims[1] == 0 || locals_[std::size_t(other)].rims[1] == 0 ||
        find(parent_[1], std::int32_t(i)) != find(parent_[1], other))
      return false;
  }
  return true;
}

bool LevelTopology::components_kept(const std::vector<Triangle>& removed, const std::vector<Triangle>& added) {
  const std::size_t n = locals_.size();
  for (int side = 0; side < 2; ++side) {
    auto& parent = parent_[side];
    parent.resize(n);
    for (std::size_t i = 0; i < n; ++i) parent[i] = std::int32_t(i);
    for (const Triangle& t : side ? added : removed) {
      unite(parent, local_[std::size_t(t[0])], local_[std::size_t(t[1])]);
      unite(parent, local_[std::size_t(t[0])], local_[std::size_t(t[2])]);
    }
  }
  // Vertices the rest of the level still uses tie the change to it.
  auto attached = [&](std::size_t i) { return uses_[std::size_t(vertex_of_[i])] - locals_[i].removed_uses > 0; };
  // Per root, on each side: whether the piece touches the rest of the level,
  // and the first such vertex (-1: none yet).
  partner_[0].assign(n, -1);
  partner_[1].assign(n, -1);
  int floating[2] = {0, 0};
  for (int side = 0; side < 2; ++side)
    for (std::size_t i = 0; i < n; ++i) {
      if ((side ? locals_[i].added_uses : locals_[i].removed_uses) == 0) continue;
      const std::int32_t root = find(parent_[side], std::int32_t(i));
      if (attached(i)) partner_[side][std::size_t(root)] = std::int32_t(i);
    }
  for (int side = 0; side < 2; ++side)
    for (std::size_t i = 0; i < n; ++i)
      if ((side ? locals_[i].added_uses : locals_[i].removed_uses) > 0 && find(parent_[side], std::int32_t(i)) == std::int32_t(i) &&
          partner_[side][i] < 0)
        ++floating[side];
  if (floating[1] != floating[0]) return false;
  // What one removed piece joined, one added piece joins.
  for (std::size_t i = 0; i < n; ++i) {
    if (locals_[i].removed_uses == 0 || !attached(i)) continue;
    const std::int32_t other = partner_[0][std::size_t(find(parent_[0], std::int32_t(i)))];
    if (other == std::int32_t(i)) continue;
    if (locals_[i].added_uses == 0 || locals_[std::size_t(other)].added_uses == 0 ||
        find(parent_[1], std::int32_t(i)) != find(parent_[1], other))
      return false;
  }
  return true;
}

// The Euler characteristic (vertices - edges + triangles in use) must not
// fall: a change may close a handle or a hole, not open a tunnel between two
// sheets.
bool LevelTopology::euler_kept(std::size_t removed, std::size_t added) const {
  long change = long(added) - long(removed);
  for (std::size_t i = 0; i < locals_.size(); ++i) {
    const std::int32_t before = uses_[std::size_t(vertex_of_[i])], after = before - locals_[i].removed_uses + locals_[i].added_uses;
    change += long(after > 0) - long(before > 0);
  }
  for (const EdgeUse& e : edges_) {
    const std::int32_t before = e.before, after = before - e.removed + e.added;
    change -= long(after > 0) - long(before > 0);
  }
  return change >= 0;
}

bool LevelTopology::keeps_topology(const std::vector<Triangle>& removed, const std::vector<Triangle>& added) {
  gather(removed, added);
  const bool kept = boundary_kept() && components_kept(removed, added) && euler_kept(removed.size(), added.size());
  release();
  return kept;
}

bool sound_level(const MeshTopology& level, const MeshTopology& full) {
  auto twice_genus = [](const MeshTopology& m) {
    return 2 * long(m.components) - long(m.boundary_loops) - m.euler_characteristic;
  };
  return level.non_manifold_edges == 0 && level.boundary_loops <= full.boundary_loops &&
         level.components <= full.components && twice_genus(level) <= twice_genus(full);
}

void LevelTopology::commit() {
  for (const EdgeUse& e : edges_)
    if (e.added != e.removed) change_edge(e.slot, e.added - e.removed);
  for (std::size_t i = 0; i < locals_.size(); ++i)
    uses_[std::size_t(vertex_of_[i])] += locals_[i].added_uses - locals_[i].removed_uses;
  edges_.clear();
  locals_.clear();
  vertex_of_.clear();
}

void LevelTopology::replace(const std::vector<Triangle>& removed, const std::vector<Triangle>& added) {
  gather(removed, added);
  release();
  commit();
}

}  // namespace scan2lod
