// Graph partitions for the cluster hierarchy, by METIS (Karypis and Kumar,
// *A Fast and High Quality Multilevel Scheme for Partitioning Irregular
// Graphs*, 1998): clusters into groups. A partition that cuts little shared
// border gives groups whose borders are short, and the next round's groups
// straddle them, which is what lets every border be simplified one round up.
#pragma once

#include <scan2lod/core/types.h>

#include <cstdint>
#include <vector>

namespace scan2lod {

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
