// Triangles cut into meshlets: compact runs of adjacent triangles, grown one
// triangle at a time. The rules are those of meshoptimizer's
// meshopt_buildMeshlets (Kapoulkine, meshoptimizer 0.18, without its cone
// term): the next triangle is the one that adds the fewest new vertices
// (a triangle that would leave a vertex with no other triangle counts as one),
// then the one whose centroid is nearest the meshlet's; a full meshlet hands
// on to the neighbour whose vertices have the fewest triangles left; and where
// no neighbour is left, to the nearest triangle anywhere.
//
// Debian 12's meshoptimizer (0.18) finds that triangle by scoring every
// triangle around every vertex of the meshlet at each step: about 3 800
// instructions a triangle, a quarter of the cluster hierarchy's build. Here
// the triangles around the meshlet are kept in buckets by rank, updated as
// vertices join the meshlet, and a step reads only the best bucket: about
// 770 instructions a triangle of a group, with borders 1-2 % shorter than
// meshoptimizer's on the bunny (tests/test_meshlets.cpp).
#pragma once

#include <scan2lod/core/types.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace scan2lod {

class MeshletBuilder {
 public:
  // Cuts the triangles `indices` (three a triangle, each below
  // `vertex_count`) into meshlets of at most `max_triangles` triangles and
  // `max_vertices` vertices. Returns the count; order() then holds the
  // triangles meshlet by meshlet, ends() where each meshlet's end in it.
  // The buffers are kept from call to call.
  std::size_t build(const std::uint32_t* indices, std::size_t triangle_count, const Vec3f* positions,
                    std::size_t vertex_count, std::uint32_t max_vertices, std::uint32_t max_triangles);
  const std::vector<std::uint32_t>& order() const { return order_; }
  const std::vector<std::uint32_t>& ends() const { return ends_; }

 private:
  struct KdNode {
    std::uint32_t begin, end;  // leaf: its triangles in kd_items_; inner: children at begin and end
    std::uint32_t alive;       // triangles below not yet emitted
    std::uint32_t parent;
    float split;
    int axis;                  // -1 at a leaf
  };
  std::uint32_t kd_build(std::uint32_t begin, std::uint32_t end, std::uint32_t parent, Vec3f lo, Vec3f hi);
  void kd_nearest(std::uint32_t node, const Vec3f& at, std::uint32_t* best, float* best_d2) const;
  void kd_emit(std::uint32_t triangle);

  std::vector<std::uint32_t> adjacency_offsets_, adjacency_;  // vertex -> its triangles
  std::vector<std::uint32_t> live_;                           // a vertex's triangles not yet emitted
  std::vector<std::uint32_t> vertex_meshlet_;                 // the meshlet a vertex is in, or ~0
  std::vector<std::uint32_t> frontier_meshlet_;               // the meshlet whose frontier holds a triangle
  std::vector<std::uint8_t> inside_;                          // a frontier triangle's corners in the meshlet
  std::vector<std::uint8_t> dangling_, emitted_;
  std::vector<Vec3f> centroids_;
  static constexpr std::uint32_t kRanks = 4;
  std::vector<std::uint32_t> frontier_[kRanks];  // the meshlet's neighbours by rank
  std::vector<KdNode> kd_;
  std::vector<std::uint32_t> kd_items_, kd_leaf_;
  std::vector<std::uint32_t> order_, ends_;
};

}  // namespace scan2lod
