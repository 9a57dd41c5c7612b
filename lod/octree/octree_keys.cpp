// Cube sizes, lattice keys and neighbours of octree nodes (lod/octree/octree_build.h):
// shared by the build's phases and by unpacking a model file, which finds the
// neighbours again.
#include <scan2lod/lod/octree/octree_build.h>

namespace scan2lod {
namespace octree_build {

double node_size(const McOctree& tree, std::size_t node) {
  return tree.grid.cube_size * double(1 << (tree.depth - tree.nodes.levels[node]));
}

std::uint64_t corner_lattice_key(std::uint64_t key, int shift, int c) {
  int x, y, z;
  unpack_key(key, &x, &y, &z);
  const std::uint64_t size = 1ull << shift;
  return pack_key((std::uint64_t(x) << shift) + (c & 1) * size, (std::uint64_t(y) << shift) + ((c >> 1) & 1) * size,
                  (std::uint64_t(z) << shift) + ((c >> 2) & 1) * size);
}

std::uint64_t local_lattice_key(std::uint64_t key, int shift, int p) {
  int x, y, z;
  unpack_key(key, &x, &y, &z);
  const std::uint64_t half = 1ull << (shift - 1);
  return pack_key((std::uint64_t(x) << shift) + (p % 3) * half, (std::uint64_t(y) << shift) + (p / 3 % 3) * half,
                  (std::uint64_t(z) << shift) + (p / 9) * half);
}

// A node's neighbours in the 27 cells around it (13: itself). A neighbour is
// a child of the parent or of one of the parent's neighbours (found a level
// earlier): a scan of at most 8 children instead of a hash lookup.
void find_neighbours(std::int32_t node, McOctree* tree) {
  const OctreeNodes& nodes = tree->nodes;
  auto& around = tree->transitions.neighbours;
  int x, y, z;
  unpack_key(nodes.keys[node], &x, &y, &z);
  const std::int32_t parent = nodes.parents[node];
  for (int c = 0; c < 27; ++c) {
    if (parent < 0) {
      around[node][c] = c == 13 ? node : -1;
      continue;
    }
    const int nx = x + c % 3 - 1, ny = y + c / 3 % 3 - 1, nz = z + c / 9 - 1;
    // >> 1 rounds -1 down to -1: outside the parent's lattice too.
    const int up = ((nx >> 1) - (x >> 1) + 1) + 3 * ((ny >> 1) - (y >> 1) + 1) + 9 * ((nz >> 1) - (z >> 1) + 1);
    const std::int32_t above = around[std::size_t(parent)][up];
    std::int32_t found = -1;
    if (above >= 0) {
      const std::uint64_t key = pack_key(std::uint64_t(nx), std::uint64_t(ny), std::uint64_t(nz));
      for (std::int32_t k = nodes.first_child[above], end = k + nodes.child_counts[above]; k < end; ++k)
        if (nodes.keys[std::size_t(k)] == key) found = k;
    }
    around[node][c] = found;
  }
}

}  // namespace octree_build
}  // namespace scan2lod
