// Disjoint sets over small integer ids, with path halving: pieces of a mesh,
// loops of its open edges.
#pragma once

#include <cstdint>
#include <numeric>
#include <vector>

namespace scan2lod {

struct UnionFind {
  std::vector<std::int32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  std::int32_t find(std::int32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::int32_t a, std::int32_t b) { parent[find(a)] = find(b); }
};

}  // namespace scan2lod
