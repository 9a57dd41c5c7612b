// Graph partitions for the cluster hierarchy, by METIS (Karypis and Kumar,
// *A Fast and High Quality Multilevel Scheme for Partitioning Irregular
// Graphs*, 1998): triangles into clusters, and clusters into groups. A
// partition with few cut edges gives clusters and groups with short borders,
// which is what lets every border be simplified one round up.
#pragma once

#include "core/types.h"

#include <cstdint>
#include <vector>

namespace scan2lod {

// Parts of about `part_size` triangles (at most that many), connected where
// the mesh is, with short borders: triangles are joined across the edges they
// share, by `weld`ed vertex (weld[v]: one id for every vertex at v's position).
// @return the part of each triangle, parts numbered from 0 in the order of their
//         first triangle; *parts gets their count
std::vector<std::int32_t> partition_triangles(const Triangle* triangles, std::size_t count,
                                              const std::vector<std::int32_t>& weld, int part_size, int* parts);

// An undirected weighted graph in compressed rows (METIS's layout): the
// neighbours of node i are adjacency[first[i] .. first[i + 1]), with weights.
struct WeightedGraph {
  std::vector<std::int32_t> first{0};
  std::vector<std::int32_t> adjacency;
  std::vector<std::int32_t> weights;
  std::size_t size() const { return first.size() - 1; }
};

// Parts of about `part_size` nodes that cut the least weight.
// @return the part of each node, parts numbered from 0; *parts gets their count
std::vector<std::int32_t> partition_graph(const WeightedGraph& graph, int part_size, int* parts);

}  // namespace scan2lod
