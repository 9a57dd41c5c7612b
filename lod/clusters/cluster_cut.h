// Cuts through the cluster hierarchy (lod/clusters/cluster_hierarchy.h): which
// clusters to draw for one object-space error everywhere, for a triangle
// budget, or for a camera, and their triangles by reference.
//
// Group g is "applied" when its error, or its error projected to the screen,
// is at most the threshold t. Errors never shrink going up the DAG and group
// spheres enclose the spheres below, so the applied groups are closed
// downwards, and drawing each cluster whose own group is applied (or that is
// at full detail) and whose parent group is not gives a watertight cut.
// Each cluster decides alone: no traversal, no floating-point work per
// triangle.
#pragma once

#include <scan2lod/lod/clusters/cluster_hierarchy.h>

#include <cstdint>
#include <vector>

namespace scan2lod {

// A pinhole camera: where it is, what it looks at, which way is up.
struct CameraView {
  Vec3f eye = Vec3f::Zero();
  Vec3f target = Vec3f(0, 0, -1);
  Vec3f up = Vec3f(0, 1, 0);
  float fov_degrees = 45;   // vertical field of view
  int height = 1080;        // viewport height in pixels
};

// The clusters with own(c) <= error < parent(c), in cluster order.
void select_clusters_by_error(const ClusterHierarchy& h, float error, std::vector<std::int32_t>* selected);

// The same over the groups' ranks (ClusterHierarchy::group_ranks), which
// cuts by triangle count go by: the rank never falls going up either, so
// this cut is as watertight.
void select_clusters_by_rank(const ClusterHierarchy& h, float rank, std::vector<std::int32_t>* selected);

// The largest error of the groups that made the selected clusters: what the
// cut may deviate by (0 at full detail).
float cut_error(const ClusterHierarchy& h, const std::vector<std::int32_t>& selected);

// The clusters whose error, seen from `camera`, is at most `pixel_error`
// pixels while their parent's is more: a group's error projected at the near
// side of its sphere (a camera inside it sees the error as infinite, so the
// region around the eye stays at full detail). `projected` is scratch space
// of one float per group.
void select_clusters_for_view(const ClusterHierarchy& h, const CameraView& camera, float pixel_error,
                              std::vector<float>* projected, std::vector<std::int32_t>* selected);

// Triangles of the uniform cut at each rank where it changes: ranks[0] is 0
// (full detail), then the groups' distinct ranks rising; triangles[i] is the
// cut's count at ranks[i], never rising.
struct ClusterCutTable {
  std::vector<float> ranks;
  std::vector<std::int64_t> triangles;
};
ClusterCutTable cluster_cut_table(const ClusterHierarchy& h);

// The smallest rank whose uniform cut has at most `budget` triangles (the
// coarsest cut's when none has).
float rank_for_triangles(const ClusterCutTable& table, std::int64_t budget);

// The rank a triangle budget gets (lod/level_budget.h): rank_for_triangles',
// or, where its cut falls more than 10 % short of the budget, the next finer
// cut's when that is at most 10 % over.
float rank_for_budget(const ClusterCutTable& table, std::int64_t budget);

// Appends the selected clusters' triangles, in order.
void emit_clusters(const ClusterHierarchy& h, const std::vector<std::int32_t>& selected,
                   std::vector<Triangle>* triangles);

}  // namespace scan2lod
