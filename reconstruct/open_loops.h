// The loops that a surface's open edges form, over the edges' own vertices
// only: what hole closing measures a hole by (reconstruct() and the welded
// bricks alike).
#pragma once

#include <scan2lod/core/flat_hash.h>
#include <scan2lod/core/union_find.h>

#include <cstdint>
#include <vector>

namespace scan2lod {

struct OpenLoops {
  std::vector<std::int32_t> loop;   // per edge: its loop (a root id)
  std::vector<std::int32_t> edges;  // per root id: the loop's edges
};

// Edge: anything with vertex ids .a and .b.
template <class Edge>
OpenLoops open_loops(const std::vector<Edge>& open) {
  FlatHashMap local(open.size() * 2);
  UnionFind loops(0);
  auto local_id = [&](std::int32_t v) {
    const std::int32_t fresh = std::int32_t(loops.parent.size());
    const std::int32_t id = local.insert(std::uint64_t(std::uint32_t(v)), fresh);
    if (id == fresh) loops.parent.push_back(fresh);
    return id;
  };
  for (const Edge& e : open) loops.unite(local_id(e.a), local_id(e.b));
  OpenLoops out;
  out.edges.assign(loops.parent.size(), 0);
  out.loop.resize(open.size());
  for (std::size_t i = 0; i < open.size(); ++i) {
    out.loop[i] = loops.find(local.find(std::uint64_t(std::uint32_t(open[i].a))));
    ++out.edges[std::size_t(out.loop[i])];
  }
  return out;
}

}  // namespace scan2lod
