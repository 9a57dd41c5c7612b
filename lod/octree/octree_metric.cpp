// Phase 9 of build_mc_octree: the LOD metric (lod/octree/octree_build.h).
#include <scan2lod/lod/octree/octree_build.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace scan2lod {
namespace octree_build {
namespace {

// A triangle's corners relative to the grid origin, in double: sums of second
// moments over thousands of triangles keep their digits.
std::array<Eigen::Vector3d, 3> corners_of(const McOctree& tree, const Triangle& t) {
  const Eigen::Vector3d origin = tree.grid.origin;
  return {tree.vertices.positions[t[0]].cast<double>() - origin, tree.vertices.positions[t[1]].cast<double>() - origin,
          tree.vertices.positions[t[2]].cast<double>() - origin};
}

// A node's own triangles: their area, and the sums of their area normals and of
// their area-weighted centroids (relative to the grid origin).
struct OwnSurface {
  double area = 0.0;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero(), centre = Eigen::Vector3d::Zero();
};

OwnSurface own_surface(const McOctree& tree, std::size_t node) {
  OwnSurface own;
  for (std::int32_t t = 0; t < tree.nodes.triangle_counts[node]; ++t) {
    const auto v = corners_of(tree, tree.triangles[std::size_t(tree.nodes.first_triangle[node] + t)]);
    const Eigen::Vector3d area_normal = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]);
    own.area += area_normal.norm();
    own.normal += area_normal;
    own.centre += area_normal.norm() * (v[0] + v[1] + v[2]) / 3.0;
  }
  return own;
}

}  // namespace

std::vector<LeafSums> leaf_sums(const McOctree& tree, std::size_t internal) {
  // Only the nodes above the leaves (the first `internal`) keep sums: a
  // leaf's go straight to its parent (200 bytes a node, 57 MB for all at
  // R = 256).
  const std::size_t n = tree.size();
  std::vector<LeafSums> sums(internal);
  for (std::size_t node = n; node-- > internal;) {  // the order of the pass below
    LeafSums s;
    for (std::int32_t t = 0; t < tree.nodes.triangle_counts[node]; ++t) {
      const auto v = corners_of(tree, tree.triangles[std::size_t(tree.nodes.first_triangle[node] + t)]);
      const Eigen::Vector3d area_normal = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]);
      const double a = area_normal.norm();
      if (a <= 0.0) continue;
      const Eigen::Vector3d sum = v[0] + v[1] + v[2], unit = area_normal / a;
      s.area += a;
      s.first += a / 3.0 * sum;
      s.second += a / 12.0 * (v[0] * v[0].transpose() + v[1] * v[1].transpose() + v[2] * v[2].transpose() +
                              sum * sum.transpose());
      s.planes += a * unit * unit.transpose();
      s.offsets += a * unit * unit.dot(v[0]);
    }
    sums[std::size_t(tree.nodes.parents[node])] += s;
  }
  for (std::size_t node = internal; node-- > 1;) {  // parents come before children
    sums[std::size_t(tree.nodes.parents[node])] += sums[node];
  }
  return sums;
}

// The LOD metric of every node above the leaves (0 for leaves).
void compute_metrics(LodMetric metric, const std::vector<LeafSums>& sums, McOctree* tree) {
  const std::size_t n = tree->size();
  tree->nodes.metrics.assign(n, 0.f);
  if (metric == LodMetric::kAreaDifference) {
    for (std::size_t node = 0; node < n; ++node) {
      if (tree->is_leaf(node)) continue;
      double children = 0.0;
      for (int c = 0; c < tree->nodes.child_counts[node]; ++c)
        children += own_surface(*tree, std::size_t(tree->nodes.first_child[node] + c)).area;
      tree->nodes.metrics[node] = float(children - own_surface(*tree, node).area);
    }
    return;
  }
  // Deviation: area times the RMS distance of the leaf surface from the plane
  // of the node's own triangles, or from its best-fitting plane where the node
  // has none; plus the surface the node adds or drops (a thin part it misses, a
  // sheet the leaves lack) at a quarter of its size, or at half where the node
  // has no surface of its own left: the leaves' whole surface (an ear's tip,
  // thinner than the node) then lies about half a node from what remains. The
  // own plane sees a node whose cube is tilted or off the leaves as well as one
  // over a bend: at 80 % of the bunny's triangles it halved the error that the
  // best-fitting plane's residual alone left. The half kept the ear tips of the
  // bunny's 1000-triangle level at R = 256 (error 4.50 -> 3.64, 1e-3 of the
  // diagonal) and its 500 at R = 128 (8.88 -> 6.78); elsewhere at 500 to 20000
  // triangles (bunny at R = 64 to 256, bun000, bun000 + bun045) it moved by
  // under 2 %, but for two: +5 % and +3 % at 1000 (R = 64; bun000).
  // Ranked per triangle the expansion adds.
  for (std::size_t node = 0; node < n; ++node) {
    if (tree->is_leaf(node)) continue;
    const LeafSums& leaf = sums[node];
    const OwnSurface own = own_surface(*tree, node);
    double deviation = (own.area > 0.0 ? 0.25 : 0.5) * std::fabs(leaf.area - own.area) * node_size(*tree, node);
    if (leaf.area > 0.0) {  // else a sheet over leaves that emit nothing
      double squared;       // sum of area x squared distance
      if (own.area > 0.0 && own.normal.norm() > 0.0) {
        const Eigen::Vector3d unit = own.normal.normalized();
        const double offset = unit.dot(own.centre / own.area);
        squared = unit.dot(leaf.second * unit) - 2.0 * offset * unit.dot(leaf.first) + offset * offset * leaf.area;
      } else {
        const Eigen::Matrix3d covariance = leaf.second - leaf.first * leaf.first.transpose() / leaf.area;
        squared = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance, Eigen::EigenvaluesOnly).eigenvalues()[0];
      }
      deviation += std::sqrt(leaf.area * std::max(0.0, squared));
    }
    const int added = tree->children_triangles(node) - int(tree->nodes.triangle_counts[node]);
    tree->nodes.metrics[node] = float(deviation / double(std::max(1, added)));
  }
}

}  // namespace octree_build
}  // namespace scan2lod
