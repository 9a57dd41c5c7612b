#include <scan2lod/lod/clusters/meshlet_builder.h>

#include <algorithm>
#include <cfloat>
#include <limits>

namespace scan2lod {

namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
constexpr std::uint32_t kLeafTriangles = 16;

float distance2(const Vec3f& a, const Vec3f& b) { return (a - b).squaredNorm(); }

}  // namespace

// A KD-tree over the triangles' centroids, each node counting the triangles
// below it not yet emitted, so that the search for the nearest one left
// skips what is used up: meshlets are cut in spatial order, so the emitted
// triangles gather in whole subtrees.
std::uint32_t MeshletBuilder::kd_build(std::uint32_t begin, std::uint32_t end, std::uint32_t parent, Vec3f lo,
                                       Vec3f hi) {
  const auto node = std::uint32_t(kd_.size());
  kd_.push_back(KdNode{begin, end, 0, parent, 0.f, -1});
  int axis = -1;
  if (end - begin > kLeafTriangles) (hi - lo).maxCoeff(&axis);
  if (axis < 0 || !(hi[axis] > lo[axis])) {  // small, or every centroid in one place
    for (std::uint32_t i = begin; i < end; ++i) {
      kd_leaf_[kd_items_[i]] = node;
      kd_[node].alive += emitted_[kd_items_[i]] ? 0 : 1;
    }
    return node;
  }
  const std::uint32_t mid = begin + (end - begin) / 2;
  std::nth_element(kd_items_.begin() + begin, kd_items_.begin() + mid, kd_items_.begin() + end,
                   [&](std::uint32_t a, std::uint32_t b) { return centroids_[a][axis] < centroids_[b][axis]; });
  const float split = centroids_[kd_items_[mid]][axis];
  // The children's boxes are the parent's cut at the split, not measured
  // again: they choose the axes, which need not be tight.
  Vec3f left_hi = hi, right_lo = lo;
  left_hi[axis] = right_lo[axis] = split;
  if (!(split > lo[axis])) right_lo[axis] = lo[axis] + 0.5f * (hi[axis] - lo[axis]);  // a heap of equal keys
  const std::uint32_t left = kd_build(begin, mid, node, lo, left_hi);
  const std::uint32_t right = kd_build(mid, end, node, right_lo, hi);
  kd_[node] = KdNode{left, right, kd_[left].alive + kd_[right].alive, parent, split, axis};
  return node;
}

void MeshletBuilder::kd_nearest(std::uint32_t node, const Vec3f& at, std::uint32_t* best, float* best_d2) const {
  const KdNode& n = kd_[node];
  if (n.alive == 0) return;
  if (n.axis < 0) {
    for (std::uint32_t i = n.begin; i < n.end; ++i) {
      const std::uint32_t t = kd_items_[i];
      if (emitted_[t]) continue;
      const float d2 = distance2(centroids_[t], at);
      if (d2 < *best_d2) {
        *best_d2 = d2;
        *best = t;
      }
    }
    return;
  }
  const float delta = at[n.axis] - n.split;
  kd_nearest(delta <= 0 ? n.begin : n.end, at, best, best_d2);
  if (delta * delta <= *best_d2) kd_nearest(delta <= 0 ? n.end : n.begin, at, best, best_d2);
}

void MeshletBuilder::kd_emit(std::uint32_t triangle) {
  if (kd_.empty()) return;
  for (std::uint32_t node = kd_leaf_[triangle]; node != kNone; node = kd_[node].parent) --kd_[node].alive;
}

std::size_t MeshletBuilder::build(const std::uint32_t* indices, std::size_t triangle_count, const Vec3f* positions,
                                  std::size_t vertex_count, std::uint32_t max_vertices, std::uint32_t max_triangles) {
  order_.clear();
  ends_.clear();
  if (triangle_count == 0) return 0;
  const auto triangles = std::uint32_t(triangle_count);

  // Each vertex's triangles, and the centroids.
  adjacency_offsets_.assign(vertex_count + 1, 0);
  for (std::size_t i = 0; i < 3 * triangle_count; ++i) ++adjacency_offsets_[indices[i] + 1];
  for (std::size_t v = 0; v < vertex_count; ++v) adjacency_offsets_[v + 1] += adjacency_offsets_[v];
  live_.resize(vertex_count);
  for (std::size_t v = 0; v < vertex_count; ++v) live_[v] = adjacency_offsets_[v + 1] - adjacency_offsets_[v];
  adjacency_.resize(3 * triangle_count);
  vertex_meshlet_.assign(adjacency_offsets_.begin(), adjacency_offsets_.end() - 1);  // fill cursors for now
  centroids_.resize(triangle_count);
  for (std::uint32_t t = 0; t < triangles; ++t) {
    const std::uint32_t* c = indices + 3 * std::size_t(t);
    for (int k = 0; k < 3; ++k) adjacency_[vertex_meshlet_[c[k]]++] = t;
    centroids_[t] = (positions[c[0]] + positions[c[1]] + positions[c[2]]) / 3.f;
  }
  // The tree is built when the scans for the nearest triangle have read
  // the triangles 16 times over: most groups never need it.
  kd_.clear();
  kd_items_.resize(triangle_count);
  kd_leaf_.resize(triangle_count);
  std::size_t scanned = 0;

  vertex_meshlet_.assign(vertex_count, kNone);
  frontier_meshlet_.assign(triangle_count, kNone);
  inside_.resize(triangle_count);
  dangling_.assign(triangle_count, 0);
  for (std::size_t v = 0; v < vertex_count; ++v)
    if (live_[v] == 1) dangling_[adjacency_[adjacency_offsets_[v]]] = 1;
  emitted_.assign(triangle_count, 0);
  for (auto& bucket : frontier_) bucket.clear();
  order_.reserve(triangle_count);

  std::uint32_t meshlet = 0, meshlet_vertices = 0, meshlet_triangles = 0;
  Vec3f sum = Vec3f::Zero();
  // A frontier triangle's rank: 0 if its corners are all in the meshlet;
  // 1 if it is a vertex's last (left for a later meshlet, it would bring
  // that vertex in for itself alone); else 1 + the corners it would add.
  auto rank = [&](std::uint32_t t) -> std::uint32_t {
    return inside_[t] == 3 ? 0 : dangling_[t] ? 1 : 4 - inside_[t];
  };
  // The frontier's best triangle: least rank, then least `score`. Only the
  // first bucket with a current entry is read; entries whose triangle was
  // emitted or ranks lower now are dropped on the way.
  auto pick = [&](auto score, std::uint32_t* out_rank) {
    for (std::uint32_t r = 0; r < kRanks; ++r) {
      std::vector<std::uint32_t>& bucket = frontier_[r];
      std::uint32_t best = kNone;
      float best_score = FLT_MAX;
      std::size_t kept = 0;
      for (const std::uint32_t t : bucket) {
        if (emitted_[t] || rank(t) != r) continue;
        bucket[kept++] = t;
        const float s = score(t);
        if (s < best_score || best == kNone) {
          best = t;
          best_score = s;
        }
      }
      bucket.resize(kept);
      if (best != kNone) {
        if (out_rank) *out_rank = r;
        return best;
      }
    }
    return kNone;
  };
  auto push = [&](std::uint32_t t) { frontier_[rank(t)].push_back(t); };

  for (std::uint32_t emitted = 0; emitted < triangles; ++emitted) {
    const Vec3f center = meshlet_triangles ? Vec3f(sum / float(meshlet_triangles)) : Vec3f::Zero();
    std::uint32_t best_rank = 0;
    std::uint32_t t = pick([&](std::uint32_t u) { return distance2(centroids_[u], center); }, &best_rank);
    // A full meshlet: nearness to its centre means nothing for the next one,
    // which starts from the neighbour whose vertices have the fewest
    // triangles left. (The rank stands for the vertices the triangle adds,
    // one over, as in meshoptimizer: a meshlet hands on a little before its
    // vertex limit.)
    if (t != kNone && (meshlet_vertices + best_rank > max_vertices || meshlet_triangles >= max_triangles))
      t = pick(
          [&](std::uint32_t u) {
            const std::uint32_t* c = indices + 3 * std::size_t(u);
            return float(live_[c[0]] + live_[c[1]] + live_[c[2]]);
          },
          nullptr);
    if (t == kNone) {  // no neighbour left: the nearest triangle anywhere
      float best_d2 = FLT_MAX;
      if (kd_.empty() && scanned > 16 * std::size_t(triangles)) {
        Vec3f lo = centroids_[0], hi = centroids_[0];
        for (std::uint32_t u = 0; u < triangles; ++u) {
          kd_items_[u] = u;
          lo = lo.cwiseMin(centroids_[u]);
          hi = hi.cwiseMax(centroids_[u]);
        }
        kd_build(0, triangles, kNone, lo, hi);
      }
      if (!kd_.empty()) {
        kd_nearest(0, center, &t, &best_d2);
      } else {  // a few times a group: cheaper than the tree
        for (std::uint32_t u = 0; u < triangles; ++u)
          if (!emitted_[u] && distance2(centroids_[u], center) < best_d2) {
            best_d2 = distance2(centroids_[u], center);
            t = u;
          }
        scanned += triangles;
      }
    }
    const std::uint32_t* c = indices + 3 * std::size_t(t);
    const std::uint32_t added = std::uint32_t(vertex_meshlet_[c[0]] != meshlet) +
                                std::uint32_t(vertex_meshlet_[c[1]] != meshlet && c[1] != c[0]) +
                                std::uint32_t(vertex_meshlet_[c[2]] != meshlet && c[2] != c[0] && c[2] != c[1]);
    if (meshlet_triangles > 0 && (meshlet_vertices + added > max_vertices || meshlet_triangles >= max_triangles)) {
      ends_.push_back(std::uint32_t(order_.size()));
      ++meshlet;
      meshlet_vertices = meshlet_triangles = 0;
      sum.setZero();
      for (auto& bucket : frontier_) bucket.clear();
    }
    order_.push_back(t);
    ++meshlet_triangles;
    sum += centroids_[t];
    emitted_[t] = 1;
    kd_emit(t);
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = c[k];
      if (--live_[v] == 1) {  // v's last triangle ranks higher from now on
        for (std::uint32_t i = adjacency_offsets_[v]; i < adjacency_offsets_[v + 1]; ++i) {
          const std::uint32_t u = adjacency_[i];
          if (emitted_[u] || dangling_[u]) continue;
          dangling_[u] = 1;
          if (frontier_meshlet_[u] == meshlet && inside_[u] < 3) frontier_[1].push_back(u);
        }
      }
      if (vertex_meshlet_[v] == meshlet) continue;
      vertex_meshlet_[v] = meshlet;
      ++meshlet_vertices;
      // v's triangles have a corner more in the meshlet (each corner counts,
      // as in the ranks).
      for (std::uint32_t i = adjacency_offsets_[v]; i < adjacency_offsets_[v + 1]; ++i) {
        const std::uint32_t u = adjacency_[i];
        if (emitted_[u]) continue;
        if (frontier_meshlet_[u] != meshlet) {
          frontier_meshlet_[u] = meshlet;
          inside_[u] = 1;
          push(u);
        } else {
          const std::uint32_t before = rank(u);
          ++inside_[u];
          if (rank(u) != before) push(u);
        }
      }
    }
  }
  ends_.push_back(std::uint32_t(order_.size()));
  return ends_.size();
}

}  // namespace scan2lod
