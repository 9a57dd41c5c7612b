#include <scan2lod/lod/clusters/cluster_hierarchy.h>

#include <scan2lod/core/error.h>
#include <scan2lod/core/morton.h>
#include <scan2lod/distributed/message.h>
#include <scan2lod/distributed/work_sharing.h>
#include <scan2lod/lod/clusters/cluster_partition.h>
#include <scan2lod/lod/clusters/group_clustering.h>
#include <scan2lod/lod/clusters/group_simplify.h>
#include <scan2lod/lod/clusters/group_vertices.h>
#include <scan2lod/lod/clusters/hierarchy_ranks.h>
#include <scan2lod/lod/clusters/paged_model.h>
#include <scan2lod/lod/clusters/position_weld.h>
#include <scan2lod/lod/clusters/triangle_spool.h>

#include <scan2lod/lod/clusters/meshlet_builder.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <thread>

namespace scan2lod {
int ClusterHierarchy::levels() const {
  int top = 0;
  for (const Cluster& c : clusters) top = std::max(top, int(c.level));
  return clusters.empty() ? 0 : top + 1;
}

std::uint64_t ClusterHierarchy::stored_triangles() const {
  return spool ? spool->size() : paged ? paged->stored_triangles() : triangles.size();
}

void ClusterHierarchy::load_spooled() {
  if (!spool) return;
  triangles = spool->load();
  spool.reset();
}

namespace {

struct Sphere {
  Vec3f center = Vec3f::Zero();
  float radius = 0;
};

// The smallest-ish sphere (box centre) around some points.
Sphere points_sphere(const JoinedView<Vec3f>& positions, const Triangle* tris, std::size_t count) {
  Aabb box;
  for (std::size_t t = 0; t < count; ++t)
    for (std::int32_t v : tris[t]) box.extend(positions[std::size_t(v)]);
  Sphere s;
  s.center = 0.5f * (box.min + box.max);
  for (std::size_t t = 0; t < count; ++t)
    for (std::int32_t v : tris[t]) s.radius = std::max(s.radius, (positions[std::size_t(v)] - s.center).norm());
  return s;
}

// A sphere that encloses every one of `spheres`, a little larger so that
// rounding in the cut's projection never ranks it below one of them.
Sphere enclosing_sphere(const std::vector<Sphere>& spheres) {
  Aabb box;
  for (const Sphere& s : spheres) {
    box.extend(s.center - Vec3f::Constant(s.radius));
    box.extend(s.center + Vec3f::Constant(s.radius));
  }
  Sphere out;
  out.center = 0.5f * (box.min + box.max);
  for (const Sphere& s : spheres) out.radius = std::max(out.radius, (s.center - out.center).norm() + s.radius);
  out.radius = out.radius * (1 + 1e-5f) + 1e-6f * box.diagonal();
  return out;
}

// Buffers of the meshlet builder, kept per thread across groups: fresh ones
// for every group were page faults on every call.
struct MeshletScratch {
  GroupVertices used;  // the group's vertices, placed ones too, in order of first use
  std::vector<Vec3f> local_positions;
  std::vector<std::uint32_t> indices;
  MeshletBuilder builder;
  std::vector<Triangle> reordered;
};

// Simplified triangles cut into clusters.
struct SplitGroup {
  SimplifiedGroup simplified;
  std::vector<std::int32_t> part;  // cluster of each triangle
  int parts = 0;
};

// Triangles cut into clusters of at most `cluster_triangles` by the meshlet
// builder (a greedy walk over adjacent triangles that keeps meshlets
// compact: lod/clusters/meshlet_builder.h), reordered cluster by cluster: part[t] is t's
// cluster. Each triangle keeps its corners and their order, so the full
// mesh's clusters are the input mesh.
//
// The builder sizes and clears its per-vertex tables by the vertex count it is
// given, so a group is first renumbered onto its own vertices, in the order
// of their first use: passing the whole mesh's count made every small group
// pay for every vertex, and the build grew with the square of the mesh.
// A vertex -1 - i is the group's placed vertex i, at placed[i].
std::vector<std::int32_t> meshlet_parts(const JoinedView<Vec3f>& positions, const std::vector<Vec3f>& placed,
                                        std::vector<Triangle>* triangles, int cluster_triangles, int* parts) {
  thread_local MeshletScratch s;
  s.used.clear();
  s.indices.resize(3 * triangles->size());
  for (std::size_t t = 0; t < triangles->size(); ++t)
    for (int k = 0; k < 3; ++k) s.indices[3 * t + std::size_t(k)] = unsigned(s.used.local((*triangles)[t][std::size_t(k)]));
  const std::vector<std::int32_t>& used = s.used.global();
  s.local_positions.resize(used.size());
  for (std::size_t i = 0; i < used.size(); ++i) {
    const std::int32_t v = used[i];
    s.local_positions[i] = v >= 0 ? positions[std::size_t(v)] : placed[std::size_t(-1 - v)];
  }
  const std::size_t count =
      s.builder.build(s.indices.data(), triangles->size(), s.local_positions.data(), s.local_positions.size(), 255,
                      std::uint32_t(std::clamp(cluster_triangles, 1, 512)));
  const std::vector<std::uint32_t>& order = s.builder.order();
  const std::vector<std::uint32_t>& ends = s.builder.ends();
  std::vector<std::int32_t> part(triangles->size());
  s.reordered.resize(triangles->size());
  for (std::size_t m = 0, at = 0; m < count; ++m)
    for (; at < ends[m]; ++at) {
      s.reordered[at] = (*triangles)[order[at]];
      part[at] = std::int32_t(m);
    }
  std::copy(s.reordered.begin(), s.reordered.end(), triangles->begin());
  *parts = int(count);
  return part;
}

// Phases 2 and 3c: the full mesh, and each simplified group, cut into
// clusters. METIS made
// clusters with a little shorter borders (cuts 1.06-1.11x meshopt_simplify's
// error at 50k-100k on the bunny against 1.14x) but serialised the threads on
// its one random state: the build took 6.7x a whole meshopt_simplify to 1 %
// against 5.0x (same run).
// The group's placed vertices, if it holds any still (-1 - i), are read from
// its added_positions.
void split_group(const JoinedView<Vec3f>& positions, int cluster_triangles, SplitGroup* g) {
  std::vector<Triangle>& triangles = g->simplified.triangles;
  g->parts = 1;
  if (triangles.size() > std::size_t(cluster_triangles))
    g->part = meshlet_parts(positions, g->simplified.added_positions, &triangles, cluster_triangles, &g->parts);
  else
    g->part.assign(triangles.size(), 0);
}

// Phase 2 for a large mesh: cut into runs of about a million triangles in
// Morton order of their centroids, each run cut into clusters on its own
// core (meshlets never cross runs). One meshlet walk over 7.2 M triangles took
// 8.3 s of a 25 s hierarchy, on one core.
constexpr std::size_t kSplitRun = std::size_t(1) << 20;
// A block's full detail is cut into clusters in runs of at most this, a run
// a core.
constexpr std::size_t kSmallestRun = std::size_t(1) << 16;

// Runs work(i) for i in [0, count) on `threads` threads: OpenMP's, which
// live from call to call, so that the simplifiers' per-thread scratch (a
// group's quadrics, about a megabyte) is made once a thread, not once a
// round. Fresh threads each round made it anew: page faults on every round
// of every block.
// The first exception a job throws is rethrown once all have stopped.
template <class Work>
void on_threads(std::size_t count, int threads, Work work) {
  if (threads <= 1 || count <= 1) {
    for (std::size_t i = 0; i < count; ++i) work(i);
    return;
  }
  std::atomic<std::size_t> next{0};
  std::exception_ptr failure;
  std::mutex mutex;
#pragma omp parallel num_threads(threads)
  try {
    for (std::size_t i; (i = next++) < count;) work(i);
  } catch (...) {
    std::lock_guard<std::mutex> lock(mutex);
    if (!failure) failure = std::current_exception();
    next = count;
  }
  if (failure) std::rethrow_exception(failure);
}

// Triangles cut into clusters run by run, each run [starts[r], starts[r + 1])
// on its own core; meshlets never cross runs.
SplitGroup split_runs(const JoinedView<Vec3f>& positions, const std::vector<std::size_t>& starts, int cluster_triangles,
                      int threads, const std::function<const Triangle&(std::size_t)>& triangle) {
  const std::size_t runs = starts.size() - 1;
  std::vector<SplitGroup> parts(runs);
  on_threads(runs, threads, [&](std::size_t r) {
    std::vector<Triangle>& own = parts[r].simplified.triangles;
    own.reserve(starts[r + 1] - starts[r]);
    for (std::size_t i = starts[r]; i < starts[r + 1]; ++i) own.push_back(triangle(i));
    split_group(positions, cluster_triangles, &parts[r]);
  });
  SplitGroup full;
  full.parts = 0;
  full.simplified.triangles.reserve(starts.back() - starts.front());
  full.part.reserve(starts.back() - starts.front());
  for (SplitGroup& p : parts) {
    full.simplified.triangles.insert(full.simplified.triangles.end(), p.simplified.triangles.begin(),
                                     p.simplified.triangles.end());
    for (std::int32_t id : p.part) full.part.push_back(id + full.parts);
    full.parts += p.parts;
    p = SplitGroup();
  }
  return full;
}

SplitGroup split_large_mesh(const JoinedView<Vec3f>& positions, const std::vector<Triangle>& triangles,
                            int cluster_triangles, int threads) {
  Aabb box;
  for (std::size_t v = 0; v < positions.size(); ++v) box.extend(positions[v]);
  const Vec3f scale = (box.max - box.min).cwiseMax(Vec3f::Constant(1e-30f)).cwiseInverse() * float((1 << 20) - 1);
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Triangle& tri = triangles[t];
    const Vec3f c = (positions[std::size_t(tri[0])] + positions[std::size_t(tri[1])] + positions[std::size_t(tri[2])]) / 3.f;
    const Vec3f q = ((c - box.min).cwiseProduct(scale)).cwiseMax(Vec3f::Zero());
    order[t] = {morton_code(std::uint64_t(q.x()), std::uint64_t(q.y()), std::uint64_t(q.z())), std::uint32_t(t)};
  }
  std::sort(order.begin(), order.end());
  const std::size_t runs = (triangles.size() + kSplitRun - 1) / kSplitRun;
  std::vector<std::size_t> starts(runs + 1);
  for (std::size_t r = 0; r <= runs; ++r) starts[r] = r * triangles.size() / runs;
  return split_runs(positions, starts, cluster_triangles, threads,
                    [&](std::size_t i) -> const Triangle& { return triangles[order[i].second]; });
}

// Phase 3d: a split group's clusters appended to the hierarchy.
void append_clusters(const SplitGroup& g, std::int32_t own_group, std::uint8_t level, ClusterHierarchy* h,
                     std::vector<std::int32_t>* made) {
  const std::vector<Triangle>& triangles = g.simplified.triangles;
  const std::vector<std::int32_t>& part = g.part;
  const int parts = g.parts;
  std::vector<std::uint32_t> first(std::size_t(parts) + 1, 0);
  for (std::int32_t p : part) ++first[std::size_t(p) + 1];
  for (int p = 0; p < parts; ++p) first[std::size_t(p) + 1] += first[std::size_t(p)];
  const std::uint32_t base = std::uint32_t(h->triangles.size());
  h->triangles.resize(h->triangles.size() + triangles.size());
  std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
  for (std::size_t t = 0; t < triangles.size(); ++t)
    h->triangles[base + fill[std::size_t(part[t])]++] = triangles[t];
  for (int p = 0; p < parts; ++p) {
    Cluster c;
    c.first_triangle = base + first[std::size_t(p)];
    c.triangle_count = std::uint16_t(first[std::size_t(p) + 1] - first[std::size_t(p)]);
    c.level = level;
    c.own_group = own_group;
    c.parent_group = -1;
    made->push_back(std::int32_t(h->clusters.size()));
    h->clusters.push_back(c);
  }
}

// Phase 3a: the active clusters as a graph, joined by the vertices they
// share, weighted by how many. Bucketed, not sorted: each vertex's clusters,
// then each cluster's neighbours counted in a table (sorting the (vertex,
// cluster) and (cluster, cluster) pairs was a tenth of the blocked build, on
// one core). Neighbours in ascending order, as METIS's result depends on it.
// `last`: -1 for every vertex, and so again on return.
WeightedGraph cluster_graph(const ClusterHierarchy& h, const std::vector<std::int32_t>& active,
                            const std::vector<std::int32_t>& weld, std::vector<std::int32_t>* last) {
  // Each vertex once per cluster that uses it, numbered in order of first
  // use; uses come cluster by cluster.
  std::vector<std::int32_t> use_vertex, use_first(active.size() + 1, 0), vertex_weld, seen_by;
  for (std::size_t i = 0; i < active.size(); ++i) {
    const Cluster& c = h.clusters[std::size_t(active[i])];
    for (std::uint32_t t = c.first_triangle; t < c.first_triangle + c.triangle_count; ++t)
      for (std::int32_t v : h.triangles[t]) {
        const std::int32_t w = weld[std::size_t(v)];
        std::int32_t& id = (*last)[std::size_t(w)];
        if (id < 0) id = std::int32_t(vertex_weld.size()), vertex_weld.push_back(w), seen_by.push_back(-1);
        if (seen_by[std::size_t(id)] != std::int32_t(i)) seen_by[std::size_t(id)] = std::int32_t(i), use_vertex.push_back(id);
      }
    use_first[i + 1] = std::int32_t(use_vertex.size());
  }
  for (std::int32_t w : vertex_weld) (*last)[std::size_t(w)] = -1;
  // Each vertex's clusters, ascending (a counting sort of the uses).
  std::vector<std::int32_t> cluster_first(vertex_weld.size() + 1, 0), clusters(use_vertex.size());
  for (std::int32_t id : use_vertex) ++cluster_first[std::size_t(id) + 1];
  for (std::size_t v = 0; v < vertex_weld.size(); ++v) cluster_first[v + 1] += cluster_first[v];
  {
    std::vector<std::int32_t> fill(cluster_first.begin(), cluster_first.end() - 1);
    for (std::size_t i = 0; i < active.size(); ++i)
      for (std::int32_t u = use_first[i]; u < use_first[i + 1]; ++u)
        clusters[std::size_t(fill[std::size_t(use_vertex[std::size_t(u)])]++)] = std::int32_t(i);
  }
  WeightedGraph g;
  g.first.assign(active.size() + 1, 0);
  std::vector<std::int32_t> weight(active.size(), 0), neighbours;
  for (std::size_t i = 0; i < active.size(); ++i) {
    neighbours.clear();
    for (std::int32_t u = use_first[i]; u < use_first[i + 1]; ++u) {
      const std::size_t id = std::size_t(use_vertex[std::size_t(u)]);
      for (std::int32_t k = cluster_first[id]; k < cluster_first[id + 1]; ++k) {
        const std::int32_t j = clusters[std::size_t(k)];
        if (j == std::int32_t(i)) continue;
        if (weight[std::size_t(j)]++ == 0) neighbours.push_back(j);
      }
    }
    std::sort(neighbours.begin(), neighbours.end());
    for (std::int32_t j : neighbours) {
      g.adjacency.push_back(j);
      g.weights.push_back(weight[std::size_t(j)]);
      weight[std::size_t(j)] = 0;
    }
    g.first[i + 1] = std::int32_t(g.adjacency.size());
  }
  return g;
}

// What every block of a build shares: the mesh and its per-vertex tables,
// sized once.
struct Shared {
  // The mesh's vertices, then those the collapses placed (added between
  // rounds, never while groups are simplified).
  JoinedView<Vec3f> positions;
  std::vector<Vec3f> added_positions, added_normals;
  std::vector<Rgb> added_colors;
  const ClusterOptions* options = nullptr;
  int threads = 1;
  std::vector<std::int32_t> weld;
  // 1: shared by two groups this round; 2: shared with another block this pass.
  std::vector<std::uint8_t> locked;
  std::vector<std::int32_t> vertex_group;
  SimplifyInput input;
  float error_floor = 0;
  double simplified = 0, expected = 1;
  ClusterBuildStats stats;

  Shared() = default;
  Shared(const Shared&) = delete;  // the views point into it

  // The job whose ranks share the blocks (hierarchy_ranks.h), or null.
  WorkSharing* job() const {
    WorkSharing* j = options->sharing;
    return j && j->ranks() > 1 ? j : nullptr;
  }
  // Ranks other than 0 keep no finished clusters: only their groups' count,
  // which numbers the groups of the blocks that follow.
  bool keeps_clusters() const { return !job() || job()->rank() == 0; }

  // A group's placed vertices into the shared arrays, and `triangles` (-1 - i
  // for placed vertex i) onto their indices; each is its own weld, unlocked.
  void take_placed(std::vector<Vec3f>* placed_positions, std::vector<Vec3f>* placed_normals,
                   std::vector<Rgb>* placed_colors, Triangle* triangles, std::size_t count) {
    if (placed_positions->empty()) return;
    const std::int32_t first = std::int32_t(positions.size());
    added_positions.insert(added_positions.end(), placed_positions->begin(), placed_positions->end());
    added_normals.insert(added_normals.end(), placed_normals->begin(), placed_normals->end());
    added_colors.insert(added_colors.end(), placed_colors->begin(), placed_colors->end());
    for (std::size_t i = 0; i < placed_positions->size(); ++i) weld.push_back(first + std::int32_t(i));
    locked.resize(weld.size(), 0);
    vertex_group.resize(weld.size(), -1);
    for (std::size_t t = 0; t < count; ++t)
      for (std::int32_t& v : triangles[t])
        if (v < 0) v = first - 1 - v;
    *placed_positions = {};
    *placed_normals = {};
    *placed_colors = {};
  }
  void take_added(SimplifiedGroup* g) {
    take_placed(&g->added_positions, &g->added_normals, &g->added_colors, g->triangles.data(), g->triangles.size());
  }
};

// What a block's rounds work with besides the shared tables: their threads,
// the marks they set a vertex at a time (-1 for every vertex between uses),
// and what they read. Blocks that run side by side (a lane each) read the
// vertices there were when their pass began, and hold the vertices their
// collapses place until the block is committed, in block order: the same
// numbers as one block after the other.
struct Lane {
  int threads = 1;
  std::vector<std::int32_t>* marks = nullptr;
  SimplifyInput input;  // its positions are what the lane reads
  bool holds_placed = false;
};

// A group's placed vertices, held back: its triangles [first, end) of the
// block's, which name them -1 - i.
struct HeldPlaced {
  std::uint32_t first = 0, end = 0;
  std::vector<Vec3f> positions, normals;
  std::vector<Rgb> colors;
};

// One block's clusters while its rounds run. Clusters [0, seeds) came in
// from outside; their own_group is already the hierarchy's. Groups made here
// are numbered from 0 until the block is written.
struct Block {
  ClusterHierarchy h;
  std::vector<Sphere> sphere;    // what a parent must enclose
  std::vector<float> own_error;  // of the group that made the cluster, 0 at full detail
  std::vector<float> own_rank;   // the same in ClusterHierarchy::group_ranks' terms
  std::size_t seeds = 0;
  std::vector<std::int32_t> active;
  int round = 1;                 // the next DAG round
  std::vector<HeldPlaced> held;  // in group order, where its lane holds them
  double simplified = 0;         // triangles its groups took in, for progress
};

// A cluster into `b` as a seed, from `from`'s cluster c.
void add_seed(const Block& from, std::size_t c, Block* b) {
  Cluster cl = from.h.clusters[c];
  const std::uint32_t first = std::uint32_t(b->h.triangles.size());
  b->h.triangles.insert(b->h.triangles.end(), from.h.triangles.begin() + cl.first_triangle,
                        from.h.triangles.begin() + cl.first_triangle + cl.triangle_count);
  cl.first_triangle = first;
  b->active.push_back(std::int32_t(b->h.clusters.size()));
  b->h.clusters.push_back(cl);
  b->sphere.push_back(from.sphere[c]);
  b->own_error.push_back(from.own_error[c]);
  b->own_rank.push_back(from.own_rank[c]);
  b->seeds = b->h.clusters.size();
}

// A group's error against what its triangles can hold: a patch of radius r
// in k triangles has triangles about r / sqrt(k) across, and a deviation of
// many of them means the surface folded over itself. Measured as error *
// sqrt(k) / r: at most 1.7 on the bunny's reconstruction, 4.2 on
// bun_zipper.ply and 4.1 on a two-bunny scan set at R = 1024, whose last
// group, left mostly handles, folded into a pyramid at 43.
constexpr float kFolded = 12;
bool folded(const SimplifiedGroup& g, float radius) {
  return g.error * std::sqrt(float(std::max<std::size_t>(g.triangles.size(), 1))) > kFolded * radius;
}

// The triangles of `clusters`, over welded vertices: a group as the
// simplifier takes it.
std::vector<Triangle> welded_triangles(const Shared& s, const ClusterHierarchy& h, const std::vector<std::int32_t>& clusters) {
  std::vector<Triangle> tris;
  for (std::int32_t c : clusters) {
    const Cluster& cl = h.clusters[std::size_t(c)];
    for (std::uint32_t t = cl.first_triangle; t < cl.first_triangle + cl.triangle_count; ++t) {
      const Triangle& o = h.triangles[t];
      tris.push_back({s.weld[std::size_t(o[0])], s.weld[std::size_t(o[1])], s.weld[std::size_t(o[2])]});
    }
  }
  return tris;
}

// Phase 3d: a group that simplified becomes a DAG node over `members`; its
// output, cut into clusters, joins `next`. Vertices it placed that its lane
// holds back stay with its triangles until the block is committed.
void add_group(Shared& s, const std::vector<std::int32_t>& members, SplitGroup& made, Block* b,
               std::vector<std::int32_t>* next) {
  ClusterHierarchy& h = b->h;
  const std::int32_t group = std::int32_t(h.groups.size());
  const std::uint32_t first = std::uint32_t(h.triangles.size());
  // Deviations of successive simplifications add up (the triangle
  // inequality), so the group's error is its own plus the worst below.
  float below = 0, below_rank = 0;
  std::vector<Sphere> children;
  for (std::int32_t c : members) {
    h.clusters[std::size_t(c)].parent_group = group;
    below = std::max(below, b->own_error[std::size_t(c)]);
    below_rank = std::max(below_rank, b->own_rank[std::size_t(c)]);
    children.push_back(b->sphere[std::size_t(c)]);
  }
  const float error = std::max(below + made.simplified.error, s.error_floor);
  const float rank = std::max(below_rank + made.simplified.mean_error, s.error_floor);
  const Sphere sphere = enclosing_sphere(children);
  h.groups.push_back({{sphere.center.x(), sphere.center.y(), sphere.center.z()}, sphere.radius, error});
  h.group_ranks.push_back(rank);
  append_clusters(made, group, std::uint8_t(b->round), &h, next);
  b->sphere.resize(h.clusters.size(), sphere);
  b->own_error.resize(h.clusters.size(), error);
  b->own_rank.resize(h.clusters.size(), rank);
  SimplifiedGroup& placed = made.simplified;
  if (!placed.added_positions.empty())
    b->held.push_back({first, std::uint32_t(h.triangles.size()), std::move(placed.added_positions),
                       std::move(placed.added_normals), std::move(placed.added_colors)});
}

// The hierarchy's last steps. Where the rounds stall above kCoarsestTriangles
// (a scan whose handles edge collapse cannot remove, with every group's
// border locked), everything left is one group with no vertex locked,
// halved step after step: by edge collapse, else by clustering that keeps
// the surface sound (handles thinner than a cell close), else by clustering
// with the topology free but no piece lost, which goes under
// kSoundCutTriangles at once, so that every cut of more keeps the full
// mesh's soundness. On the pair's scans at R = 1024 (281 handles) the rounds
// stall at 4 908 triangles, which neither sound step shrinks: the cuts go on
// at 732 and 256 triangles, where one step to 256 left 232.
void finish_top(Shared& s, Lane& lane, Block* b) {
  ClusterHierarchy& h = b->h;
  const double share = s.options->reduction, stall = s.options->stall;
  while (b->round < 255) {
    const std::vector<Triangle> tris = welded_triangles(s, h, b->active);
    const std::size_t n = tris.size();
    if (n <= kCoarsestTriangles) return;
    std::size_t target = std::max(kCoarsestTriangles, std::size_t(std::ceil(double(n) * share)));
    SplitGroup top;
    top.simplified = simplify_group(tris, target, lane.input);
    if (double(top.simplified.triangles.size()) > stall * double(n) ||
        folded(top.simplified, points_sphere(lane.input.positions, tris.data(), n).radius))
      top.simplified = cluster_group(tris, target, lane.input);
    if (double(top.simplified.triangles.size()) > stall * double(n)) {
      if (n >= kSoundCutTriangles) target = std::min(target, kSoundCutTriangles - 1);
      top.simplified = cluster_group(tris, target, lane.input, ClusterSoundness::kPiecesOnly);
    }
    if (top.simplified.triangles.size() >= n) return;
    if (!lane.holds_placed) s.take_added(&top.simplified);
    split_group(lane.input.positions, s.options->cluster_triangles, &top);
    std::vector<std::int32_t> next;
    add_group(s, b->active, top, b, &next);
    b->active = std::move(next);
    ++b->round;
  }
}

// Phase 3: round after round, the block's active clusters grouped, each group
// simplified to about half and cut into new clusters, until no group
// simplifies or one cluster is left; at the `top`, finish_top. Vertices
// locked at 2 stay locked.
void run_rounds(Shared& s, Lane& lane, Block* b, int rounds = 255, bool top = false) {
  const ClusterOptions& options = *s.options;
  ClusterHierarchy& h = b->h;
  std::vector<std::int32_t>& active = b->active;
  for (int done = 0; done < rounds && active.size() > 1 && b->round < 255; ++done, ++b->round) {
    // Phase 3a: groups of neighbouring clusters.
    int group_count = 1;
    std::vector<std::int32_t> group_of(active.size(), 0);
    if (active.size() > std::size_t(options.group_clusters))
      group_of = partition_graph(cluster_graph(h, active, s.weld, lane.marks), options.group_clusters, &group_count);
    std::vector<std::vector<std::int32_t>> members;
    members.resize(std::size_t(group_count));
    for (std::size_t i = 0; i < active.size(); ++i) members[std::size_t(group_of[i])].push_back(active[i]);

    // Phase 3b: lock what more than one group uses.
    std::vector<std::int32_t> touched;
    for (std::size_t g = 0; g < members.size(); ++g)
      for (std::int32_t c : members[g]) {
        const Cluster& cl = h.clusters[std::size_t(c)];
        for (std::uint32_t t = cl.first_triangle; t < cl.first_triangle + cl.triangle_count; ++t)
          for (std::int32_t v : h.triangles[t]) {
            const std::size_t w = std::size_t(s.weld[std::size_t(v)]);
            std::int32_t& owner = (*lane.marks)[w];
            if (owner == -1) owner = std::int32_t(g), touched.push_back(std::int32_t(w));
            else if (owner != std::int32_t(g) && s.locked[w] == 0) s.locked[w] = 1;
          }
      }

    // Phase 3c: each group simplified to about half, on every core; its new
    // vertices numbered in group order (the same on any core count); then
    // each cut into clusters.
    const double share = b->round == 1 ? options.first_reduction : options.reduction;
    std::vector<SplitGroup> result(members.size());
    std::vector<std::size_t> before(members.size(), 0);
    on_threads(members.size(), lane.threads, [&](std::size_t g) {
      const std::vector<Triangle> tris = welded_triangles(s, h, members[g]);
      const std::size_t n = tris.size();
      before[g] = n;
      const std::size_t target = std::size_t(std::ceil(double(n) * share));
      const CollapseSequence sequence = simplify_steps(tris, target, lane.input);
      std::size_t step = sequence.steps();
      SimplifiedGroup& simplified = result[g].simplified;
      simplified = sequence.take(step, lane.input);
      // Folded: collapses that only handles left room for dragged the
      // surface across the group. Fewer of them, else none.
      const float radius = points_sphere(lane.input.positions, tris.data(), n).radius;
      for (double lighter : {0.5 * (1 + share), options.stall, 1.0}) {
        if (!folded(simplified, radius)) break;
        step = lighter == 1.0 ? 0 : std::min(step, sequence.step_keeping(std::size_t(std::ceil(double(n) * lighter))));
        simplified = sequence.take(step, lane.input);
      }
      if (double(simplified.triangles.size()) > options.stall * double(n)) {
        // Stalled: collapses cannot remove what is left (handles, mostly).
        // Clustering the group as it came in, instead.
        simplified = cluster_group(tris, target, lane.input);
      }
    });
    std::vector<std::uint8_t> simplifies(members.size(), 0);
    for (std::size_t g = 0; g < members.size(); ++g) {
      const std::size_t kept = result[g].simplified.triangles.size();
      simplifies[g] = kept > 0 && double(kept) <= options.stall * double(before[g]);
      if (simplifies[g] && !lane.holds_placed) s.take_added(&result[g].simplified);
    }
    on_threads(members.size(), lane.threads, [&](std::size_t g) {
      if (simplifies[g]) split_group(lane.input.positions, options.cluster_triangles, &result[g]);
    });
    for (std::int32_t v : touched) {
      (*lane.marks)[std::size_t(v)] = -1;
      if (s.locked[std::size_t(v)] == 1) s.locked[std::size_t(v)] = 0;
    }

    // Phase 3d: groups that simplified become DAG nodes; their output becomes
    // clusters of the next round. The others' clusters wait for new neighbours.
    std::vector<std::int32_t> next;
    bool progress = false;
    for (std::size_t g = 0; g < members.size(); ++g) {
      b->simplified += double(before[g]);
      const bool stalled = result[g].parts == 0;
      if (stalled) {
        next.insert(next.end(), members[g].begin(), members[g].end());
        continue;
      }
      progress = true;
      add_group(s, members[g], result[g], b, &next);
    }
    if (!lane.holds_placed) {
      s.simplified += b->simplified;
      b->simplified = 0;
      if (options.progress) options.progress(std::min(1.0, s.simplified / s.expected));
    }
    active = std::move(next);
    if (!progress) break;
  }
  if (top) finish_top(s, lane, b);
}

// Phase 4: a block's finished clusters (those with a parent, or all of them
// when `last`) into `out`, its groups numbered on from out's; the others
// become seeds of `carried`, to be grouped across the block's border in the
// next pass. Without `keep`, finished clusters are dropped (a rank that
// only makes blocks for rank 0).
void write_block(Block& b, bool last, bool keep, ClusterHierarchy* out, Block* carried, TriangleSpool* spool) {
  const std::int32_t offset = std::int32_t(out->groups.size());
  out->groups.insert(out->groups.end(), b.h.groups.begin(), b.h.groups.end());
  out->group_ranks.insert(out->group_ranks.end(), b.h.group_ranks.begin(), b.h.group_ranks.end());
  auto global = [offset](std::int32_t local) { return local < 0 ? local : local + offset; };
  for (std::size_t c = 0; c < b.h.clusters.size(); ++c) {
    Cluster& cl = b.h.clusters[c];
    if (c >= b.seeds) cl.own_group = global(cl.own_group);
    cl.parent_group = global(cl.parent_group);
    if (cl.parent_group < 0 && !last) {
      add_seed(b, c, carried);
      continue;
    }
    if (!keep) continue;
    const Triangle* from = &b.h.triangles[cl.first_triangle];
    if (spool) {
      cl.first_triangle = std::uint32_t(spool->size());
      spool->append(from, cl.triangle_count);
    } else {
      cl.first_triangle = std::uint32_t(out->triangles.size());
      out->triangles.insert(out->triangles.end(), from, from + cl.triangle_count);
    }
    out->clusters.push_back(cl);
  }
  b = Block();
}

// Marks with 2 in s.locked the vertices that blocks share. `each(visit)`
// calls visit(triangle, block) for every triangle of the pass; vertex_group
// serves as each vertex's first block and is left at -1.
template <class Each>
void lock_block_borders(Shared& s, Each each) {
  std::vector<std::int32_t> touched;
  each([&](const Triangle& t, std::int32_t block) {
    for (std::int32_t v : t) {
      const std::size_t w = std::size_t(s.weld[std::size_t(v)]);
      std::int32_t& first = s.vertex_group[w];
      if (first == -1) first = block, touched.push_back(std::int32_t(w));
      else if (first != block) s.locked[w] = 2;
    }
  });
  for (std::int32_t v : touched) s.vertex_group[std::size_t(v)] = -1;
}

// Splits [begin, end) of `triangles` until its parts hold at most `block`,
// appending their starts in order; the two halves of a split on threads of
// their own while `threads` allows (the splits and sorts were 5-8 % of a
// blocked build, on one core).
void kd_split(const JoinedView<Vec3f>& positions, std::vector<Triangle>* triangles, std::size_t begin,
              std::size_t end, std::size_t block, int threads, std::vector<std::size_t>* starts) {
  auto centroid = [&](const Triangle& t) {
    return positions[std::size_t(t[0])] + positions[std::size_t(t[1])] + positions[std::size_t(t[2])];
  };
  // Along `axis` first, then the other axes, then the corners: two
  // triangles compare equal only where they are the same triangle.
  auto before = [&](int axis) {
    return [&, axis](const Triangle& a, const Triangle& b) {
      const Vec3f ca = centroid(a), cb = centroid(b);
      for (int k = 0; k < 3; ++k) {
        const int i = (axis + k) % 3;
        if (ca[i] != cb[i]) return ca[i] < cb[i];
      }
      for (int c = 0; c < 3; ++c)
        for (int i = 0; i < 3; ++i) {
          const float pa = positions[std::size_t(a[std::size_t(c)])][i], pb = positions[std::size_t(b[std::size_t(c)])][i];
          if (pa != pb) return pa < pb;
        }
      return false;
    };
  };
  if (end - begin <= block) {
    // Sorted across the block's longest side, so that its runs (a core
    // each, in the first pass) are a KD split too; the centroids are taken
    // once, as the comparator alone loads six vertices from all over.
    std::vector<std::pair<Vec3f, std::uint32_t>> keys(end - begin);
    Aabb box;
    for (std::size_t i = begin; i < end; ++i) {
      keys[i - begin] = {centroid((*triangles)[i]), std::uint32_t(i)};
      box.extend(keys[i - begin].first);
    }
    int axis = 0;
    box.extent().maxCoeff(&axis);
    const auto tied = before(axis);
    std::sort(keys.begin(), keys.end(), [&](const auto& a, const auto& b) {
      for (int k = 0; k < 3; ++k) {
        const int i = (axis + k) % 3;
        if (a.first[i] != b.first[i]) return a.first[i] < b.first[i];
      }
      return tied((*triangles)[a.second], (*triangles)[b.second]);
    });
    std::vector<Triangle> sorted(end - begin);
    for (std::size_t i = 0; i < keys.size(); ++i) sorted[i] = (*triangles)[keys[i].second];
    std::copy(sorted.begin(), sorted.end(), triangles->begin() + std::ptrdiff_t(begin));
    starts->push_back(begin);
    return;
  }
  Aabb box;
  for (std::size_t i = begin; i < end; ++i) box.extend(centroid((*triangles)[i]));
  int axis = 0;
  box.extent().maxCoeff(&axis);
  const std::size_t middle = begin + (end - begin) / 2;
  std::nth_element(triangles->begin() + std::ptrdiff_t(begin), triangles->begin() + std::ptrdiff_t(middle),
                   triangles->begin() + std::ptrdiff_t(end), before(axis));
  if (threads < 2) {
    kd_split(positions, triangles, begin, middle, block, 1, starts);
    kd_split(positions, triangles, middle, end, block, 1, starts);
    return;
  }
  std::vector<std::size_t> upper;
  std::thread other([&] { kd_split(positions, triangles, middle, end, block, threads / 2, &upper); });
  kd_split(positions, triangles, begin, middle, block, threads - threads / 2, starts);
  other.join();
  starts->insert(starts->end(), upper.begin(), upper.end());
}

// Phase 1 of a blocked build: the triangles reordered in place into blocks
// of at most `block`, by halving at the median centroid across the longest
// side of each part's box, as a KD-tree does (Nexus cuts its first blocks
// so): straight borders, the shortest a cut into boxes gives. (Runs of the
// Morton curve had staircase borders, and cuts up to 1.4x the in-core
// error at 20 k-50 k triangles of 3.3 M.) Returns the blocks' starts, the
// end last.
//
// The blocks and the order inside each depend on the triangles' positions
// alone, not on the order they came in nor on the core count: the median
// by a total order, each block sorted by it at the end, across its own
// longest side. A surface welded from bricks numbers its triangles
// otherwise than one made in core; the same blocks make it the same
// hierarchy.
std::vector<std::size_t> kd_blocks(const JoinedView<Vec3f>& positions, std::vector<Triangle>* triangles,
                                   std::size_t block, int threads) {
  std::vector<std::size_t> starts;
  kd_split(positions, triangles, 0, triangles->size(), block, threads, &starts);
  starts.push_back(triangles->size());
  return starts;
}

// Phase 2a: block [begin, end) of the full triangles, its first round: cut
// into clusters in runs of at most kSmallestRun along the block's longest
// side, as the blocks were cut, and by size, not by core count (the same
// clusters on any machine); then grouped and simplified.
Block first_round(Shared& s, Lane& lane, const Triangle* begin, const Triangle* end, int round) {
  const std::size_t size = std::size_t(end - begin);
  const std::size_t parts = std::max<std::size_t>(1, (size + kSmallestRun - 1) / kSmallestRun);
  std::vector<std::size_t> runs(parts + 1);
  for (std::size_t p = 0; p <= parts; ++p) runs[p] = p * size / parts;
  SplitGroup full = split_runs(lane.input.positions, runs, s.options->cluster_triangles, lane.threads,
                               [begin](std::size_t i) -> const Triangle& { return begin[i]; });
  Block one;
  append_clusters(full, -1, 0, &one.h, &one.active);
  full = SplitGroup();
  for (const Cluster& c : one.h.clusters)
    one.sphere.push_back(points_sphere(lane.input.positions, &one.h.triangles[c.first_triangle], c.triangle_count));
  one.own_error.assign(one.h.clusters.size(), 0.f);
  one.own_rank.assign(one.h.clusters.size(), 0.f);
  one.seeds = one.h.clusters.size();
  one.round = round;
  run_rounds(s, lane, &one, 1);
  return one;
}

// Phase 2b: a block whose lane held its placed vertices, committed: they
// join the shared arrays (numbered as if the blocks had run one after the
// other), then the block is written.
void commit_block(Shared& s, Block& b, ClusterHierarchy* out, Block* carried, TriangleSpool* spool) {
  for (HeldPlaced& p : b.held) {
    if (s.weld.size() + p.positions.size() > s.weld.capacity())
      throw std::logic_error("cluster hierarchy: more placed vertices than room was made for");
    s.take_placed(&p.positions, &p.normals, &p.colors, &b.h.triangles[p.first], p.end - p.first);
  }
  b.held.clear();
  s.simplified += b.simplified;
  b.simplified = 0;
  if (s.options->progress) s.options->progress(std::min(1.0, s.simplified / s.expected));
  write_block(b, false, s.keeps_clusters(), out, carried, spool);
}

// The lanes of a pass whose blocks run side by side: room in the shared
// tables for every vertex the pass can place (at most three a triangle), so
// that commits never move the tables the lanes read; each lane reading the
// vertices there were when the pass began and holding back those it places;
// marks of their own but for the first lane's. One lane takes every thread.
struct PassLanes {
  std::vector<std::vector<std::int32_t>> own_marks;
  std::vector<Lane> lanes;
};
void make_lanes(Shared& s, Lane& main, std::size_t pass_triangles, std::size_t lane_count, PassLanes* out) {
  const std::size_t room = 3 * pass_triangles;
  s.weld.reserve(s.weld.size() + room);
  s.locked.reserve(s.locked.size() + room);
  s.vertex_group.reserve(s.vertex_group.size() + room);
  s.added_positions.reserve(s.added_positions.size() + room);
  if (!s.input.normals.empty()) s.added_normals.reserve(s.added_normals.size() + room);
  if (!s.input.colors.empty()) s.added_colors.reserve(s.added_colors.size() + room);
  out->own_marks.resize(lane_count > 0 ? lane_count - 1 : 0);
  out->lanes.resize(lane_count);
  for (std::size_t l = 0; l < lane_count; ++l) {
    Lane& lane = out->lanes[l];
    lane.threads = lane_count == 1 ? main.threads : 1;
    lane.holds_placed = true;
    lane.input = s.input;
    lane.input.positions = s.input.positions.frozen();
    lane.input.normals = s.input.normals.frozen();
    lane.input.colors = s.input.colors.frozen();
    if (l == 0) {
      lane.marks = main.marks;
    } else {
      out->own_marks[l - 1].assign(s.vertex_group.size(), -1);
      lane.marks = &out->own_marks[l - 1];
    }
  }
}

// ---- blocks sent between ranks --------------------------------------------

}  // namespace

template <>
struct TravelsAsBytes<Sphere> : std::true_type {};

namespace {

std::string packed_block(const Block& b) {
  MessageWriter out;
  out.put(b.h.clusters), out.put(b.h.triangles), out.put(b.h.groups), out.put(b.h.group_ranks);
  out.put(b.sphere), out.put(b.own_error), out.put(b.own_rank), out.put(b.active);
  out.put(std::uint64_t(b.seeds)), out.put(std::int32_t(b.round)), out.put(b.simplified);
  out.put(std::uint64_t(b.held.size()));
  for (const HeldPlaced& p : b.held) {
    out.put(p.first), out.put(p.end);
    out.put(p.positions), out.put(p.normals), out.put(p.colors);
  }
  return std::move(out.bytes());
}

Block unpacked_block(const std::string& bytes) {
  MessageReader in(bytes);
  Block b;
  in.get(&b.h.clusters), in.get(&b.h.triangles), in.get(&b.h.groups), in.get(&b.h.group_ranks);
  in.get(&b.sphere), in.get(&b.own_error), in.get(&b.own_rank), in.get(&b.active);
  std::uint64_t seeds = 0, held = 0;
  std::int32_t round = 0;
  in.get(&seeds), in.get(&round), in.get(&b.simplified);
  b.seeds = std::size_t(seeds), b.round = round;
  in.get(&held);
  b.held.resize(std::size_t(held));
  for (HeldPlaced& p : b.held) {
    in.get(&p.first), in.get(&p.end);
    in.get(&p.positions), in.get(&p.normals), in.get(&p.colors);
  }
  return b;
}

// Rank `root`'s bytes on every rank.
void broadcast_bytes(WorkSharing& job, int root, std::string* bytes) {
  std::uint64_t size = bytes->size();
  job.broadcast_from(root, &size, sizeof size);
  if (job.rank() != root) bytes->assign(std::size_t(size), '\0');
  job.broadcast_from(root, bytes->data(), bytes->size());
}

// A pass's blocks across the ranks of a job: rank b mod N makes block b, on
// its lanes (a thread each, or one lane with every thread), at most a few
// blocks ahead of the commits; the main thread commits every block in block
// order, its own and those the others send, and is the only thread that
// talks to the other ranks. Every rank thus ends the pass with the same
// tables, clusters carried and group count; blocks are made as lanes make
// them in one process (placed vertices held back), so the numbers are the
// single process's.
template <class Make>
void blocks_across_ranks(Shared& s, Lane& main, std::size_t blocks, std::size_t pass_triangles, Make make,
                         ClusterHierarchy* out, Block* carried, TriangleSpool* spool) {
  WorkSharing& job = *s.job();
  const std::size_t ranks = std::size_t(job.ranks()), rank = std::size_t(job.rank());
  std::vector<std::size_t> own;
  for (std::size_t b = rank; b < blocks; b += ranks) own.push_back(b);
  s.stats.blocks_here += own.size();
  const int asked = s.options->lanes > 0 ? std::min(s.options->lanes, main.threads) : main.threads;
  const std::size_t lane_count = std::min<std::size_t>(std::size_t(std::max(asked, 1)), own.size());
  PassLanes pass;
  make_lanes(s, main, pass_triangles, lane_count, &pass);
  const std::size_t window = 2 * std::max<std::size_t>(lane_count, 1);
  std::vector<Block> finished(own.size());
  std::vector<std::uint8_t> ready(own.size(), 0);
  std::size_t next_own = 0, committed_own = 0;
  std::exception_ptr failure;
  std::mutex mutex;
  std::condition_variable changed;
  auto run = [&](Lane& lane) {
    for (;;) {
      std::size_t i;
      {
        std::unique_lock<std::mutex> lock(mutex);
        changed.wait(lock, [&] { return failure || next_own >= own.size() || next_own < committed_own + window; });
        if (failure || next_own >= own.size()) return;
        i = next_own++;
      }
      try {
        Block one = make(lane, own[i]);
        std::lock_guard<std::mutex> lock(mutex);
        finished[i] = std::move(one);
        ready[i] = 1;
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!failure) failure = std::current_exception();
      }
      changed.notify_all();
    }
  };
  std::vector<std::thread> threads;
  for (Lane& lane : pass.lanes) threads.emplace_back(run, std::ref(lane));
  try {
    for (std::size_t b = 0; b < blocks; ++b) {
      const int maker = int(b % ranks);
      std::string bytes;
      Block one;
      if (std::size_t(maker) == rank) {
        const std::size_t i = b / ranks;
        {
          std::unique_lock<std::mutex> lock(mutex);
          changed.wait(lock, [&] { return failure || ready[i]; });
          if (failure) std::rethrow_exception(failure);
          one = std::move(finished[i]);
        }
        bytes = packed_block(one);
      }
      broadcast_bytes(job, maker, &bytes);
      s.stats.bytes_exchanged += double(bytes.size());
      if (std::size_t(maker) != rank) one = unpacked_block(bytes);
      bytes = std::string();
      commit_block(s, one, out, carried, spool);
      if (std::size_t(maker) == rank) {
        std::lock_guard<std::mutex> lock(mutex);
        ++committed_own;
      }
      changed.notify_all();
    }
  } catch (...) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (!failure) failure = std::current_exception();
    }
    changed.notify_all();
    for (std::thread& t : threads) t.join();
    throw;
  }
  for (std::thread& t : threads) t.join();
}

// One round of every block of a pass: `make(lane, b)` makes block b's.
// Blocks share only the vertices on their borders, locked, so they run side
// by side, a lane a core: each reads the vertices there were when the pass
// began, holds back the vertices it places, and is committed in block order
// (the serial parts of a block, its cluster graph and partition, then
// overlap another's collapses: they were a fifth of the stage on one core).
// A lane never runs more than a few blocks ahead of the commits, so that
// finished blocks do not pile up. `pass_triangles`: the pass's triangles.
template <class Make>
void blocks_side_by_side(Shared& s, Lane& main, std::size_t blocks, std::size_t pass_triangles, Make make,
                         ClusterHierarchy* out, Block* carried, TriangleSpool* spool) {
  s.stats.blocks += blocks;
  if (s.job()) return blocks_across_ranks(s, main, blocks, pass_triangles, make, out, carried, spool);
  s.stats.blocks_here += blocks;
  const int asked = s.options->lanes > 0 ? std::min(s.options->lanes, main.threads) : main.threads;
  const std::size_t lane_count = std::min<std::size_t>(std::size_t(std::max(asked, 1)), blocks);
  if (lane_count <= 1) {
    for (std::size_t b = 0; b < blocks; ++b) {
      Block one = make(main, b);
      commit_block(s, one, out, carried, spool);
    }
    return;
  }
  PassLanes pass;
  make_lanes(s, main, pass_triangles, lane_count, &pass);
  std::vector<Lane>& lanes = pass.lanes;
  const std::size_t window = 2 * lane_count;
  std::vector<Block> finished(blocks);
  std::vector<std::uint8_t> ready(blocks, 0);
  std::size_t next_block = 0, next_commit = 0;
  std::exception_ptr failure;
  std::mutex mutex;
  std::condition_variable changed;
  auto run = [&](Lane& lane) {
    for (;;) {
      std::size_t b;
      {
        std::unique_lock<std::mutex> lock(mutex);
        changed.wait(lock, [&] { return failure || next_block >= blocks || next_block < next_commit + window; });
        if (failure || next_block >= blocks) return;
        b = next_block++;
      }
      try {
        Block one = make(lane, b);
        std::lock_guard<std::mutex> lock(mutex);
        finished[b] = std::move(one);
        ready[b] = 1;
        for (; next_commit < blocks && ready[next_commit]; ++next_commit)
          commit_block(s, finished[next_commit], out, carried, spool);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!failure) failure = std::current_exception();
      }
      changed.notify_all();
    }
  };
  std::vector<std::thread> others;
  for (std::size_t l = 1; l < lane_count; ++l) others.emplace_back(run, std::ref(lanes[l]));
  run(lanes[0]);
  for (std::thread& t : others) t.join();
  if (failure) std::rethrow_exception(failure);
}

// The blocked build, one DAG round a pass, as Ponchio's Nexus builds a level
// at a time. Pass 1 cuts the full mesh into KD-tree blocks (kd_blocks) and
// makes each block's full-detail clusters; each later pass cuts the active
// clusters into blocks with METIS over the vertices they share, which cuts
// where clusters share few, inside the last pass's blocks, so that a pass's
// block borders are simplified in the next. Each block runs one round with
// the vertices it shares with other blocks locked, and what is left active
// goes on; once it fits one block, the rounds run to the top in it.
ClusterHierarchy build_in_blocks(Shared& s, Lane& main, std::vector<Triangle> triangles, std::int64_t block_triangles) {
  const ClusterOptions& options = *s.options;
  std::size_t block = std::max<std::size_t>(std::size_t(block_triangles), 1024);
  ClusterHierarchy out;
  out.full_triangles = std::int64_t(triangles.size());
  TriangleSpool* spool = options.spool.get();
  // The first round keeps about two thirds, each later one about half: the
  // hierarchy holds about 2.3 times the full detail. Reserved, so that
  // growth never doubles it.
  if (!spool && s.keeps_clusters()) out.triangles.reserve(std::size_t(2.4 * double(triangles.size())) + 4096);
  Block carried;
  int round = 1;
  {
    const std::vector<std::size_t> starts = kd_blocks(s.positions, &triangles, block, s.threads);
    const std::size_t blocks = starts.size() - 1;
    lock_block_borders(s, [&](auto visit) {
      for (std::size_t b = 0; b < blocks; ++b)
        for (std::size_t i = starts[b]; i < starts[b + 1]; ++i) visit(triangles[i], std::int32_t(b));
    });
    blocks_side_by_side(
        s, main, blocks, triangles.size(),
        [&](Lane& lane, std::size_t b) {
          return first_round(s, lane, triangles.data() + starts[b], triangles.data() + starts[b + 1], round);
        },
        &out, &carried, spool);
    for (std::uint8_t& l : s.locked) l = 0;
  }
  triangles = std::vector<Triangle>();
  for (std::size_t before = std::size_t(-1);;) {
    ++round;
    const std::size_t left = carried.h.triangles.size();

    if (left <= block || carried.h.clusters.size() <= std::size_t(options.group_clusters) || round >= 254) {
      if (!s.keeps_clusters()) return out;  // the rounds to the top run on rank 0 alone
      carried.round = round;
      run_rounds(s, main, &carried, 255, true);
      write_block(carried, true, true, &out, nullptr, spool);
      out.spool = options.spool;
      return out;
    }
    // A pass that simplified little had blocks too small for the groups
    // its borders cut: the next one's are twice as large.
    if (double(left) > 0.9 * double(before)) block *= 2;
    before = left;
    // Blocks by METIS over the cluster graph: it cuts where clusters share
    // few vertices, which is inside the last pass's blocks (simplified)
    // rather than along their borders (still at the detail they came in).
    const std::size_t n = carried.h.clusters.size();
    std::vector<std::int32_t> all(n);
    std::iota(all.begin(), all.end(), 0);
    int parts = 1;
    const int per_block = int(std::max<std::size_t>(2, block * n / left));
    const std::vector<std::int32_t> part = partition_graph(cluster_graph(carried.h, all, s.weld, main.marks), per_block, &parts);
    std::vector<std::size_t> starts(std::size_t(parts) + 1, 0);
    for (std::int32_t p : part) ++starts[std::size_t(p) + 1];
    for (std::size_t b = 0; b < std::size_t(parts); ++b) starts[b + 1] += starts[b];
    std::vector<std::uint32_t> order(n);  // clusters block by block
    {
      std::vector<std::size_t> fill(starts.begin(), starts.end() - 1);
      for (std::size_t c = 0; c < n; ++c) order[fill[std::size_t(part[c])]++] = std::uint32_t(c);
    }
    const std::size_t blocks = std::size_t(parts);
    lock_block_borders(s, [&](auto visit) {
      for (std::size_t b = 0; b < blocks; ++b)
        for (std::size_t i = starts[b]; i < starts[b + 1]; ++i) {
          const Cluster& cl = carried.h.clusters[order[i]];
          for (std::uint32_t t = cl.first_triangle; t < cl.first_triangle + cl.triangle_count; ++t)
            visit(carried.h.triangles[t], std::int32_t(b));
        }
    });
    Block next;
    blocks_side_by_side(
        s, main, blocks, left,
        [&](Lane& lane, std::size_t b) {
          Block one;
          for (std::size_t i = starts[b]; i < starts[b + 1]; ++i) add_seed(carried, order[i], &one);
          one.round = round;
          run_rounds(s, lane, &one, 1);
          return one;
        },
        &out, &next, spool);
    carried = std::move(next);
    for (std::uint8_t& l : s.locked) l = 0;
  }
}

}  // namespace

std::vector<ClusterPage> cluster_pages(const ClusterHierarchy& h) {
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  std::vector<ClusterPage> pages;
  std::vector<Sphere> spheres;
  auto close = [&] {
    ClusterPage& p = pages.back();
    if (spheres.empty()) {
      p.center[0] = p.center[1] = p.center[2] = 0;
      p.radius = kInfinity;
    } else {
      const Sphere s = enclosing_sphere(spheres);
      for (int k = 0; k < 3; ++k) p.center[k] = s.center[k];
      p.radius = s.radius;
    }
    spheres.clear();
  };
  std::uint64_t triangles = 0;
  for (std::size_t c = 0; c < h.clusters.size(); ++c) {
    const Cluster& cl = h.clusters[c];
    const bool joins = !pages.empty() && triangles + cl.triangle_count <= kPageTriangles &&
                       h.clusters[c - 1].first_triangle + h.clusters[c - 1].triangle_count == cl.first_triangle;
    if (!joins) {
      if (!pages.empty()) close();
      pages.push_back({std::uint32_t(c), 0, {0, 0, 0}, 0, kInfinity, 0});
      triangles = 0;
    }
    ClusterPage& p = pages.back();
    ++p.cluster_count;
    triangles += cl.triangle_count;
    p.min_error = std::min(p.min_error, cl.own_group < 0 ? 0.f : h.groups[std::size_t(cl.own_group)].error);
    p.max_error = std::max(p.max_error, cl.parent_group < 0 ? kInfinity : h.groups[std::size_t(cl.parent_group)].error);
    // A cluster lies in its parent group's sphere, or at the top in its own group's.
    const std::int32_t g = cl.parent_group >= 0 ? cl.parent_group : cl.own_group;
    if (g >= 0) {
      const GroupBound& b = h.groups[std::size_t(g)];
      Sphere s;
      s.center = Vec3f(b.center[0], b.center[1], b.center[2]);
      s.radius = b.radius;
      spheres.push_back(s);
    }
  }
  if (!pages.empty()) close();
  return pages;
}

std::int64_t block_triangles_for(std::int64_t options_block, std::size_t triangles) {
  const std::int64_t block = options_block == kAutomaticBlocks
                                 ? (std::int64_t(triangles) > kWholeMeshTriangles ? kBlockTriangles : 0)
                                 : options_block;
  return block > 0 && std::int64_t(triangles) > block ? block : 0;
}

namespace {

// Phase 0: the tables every block reads, and the lane that runs alone.
void prepare(Shared& s, Lane& main, ArrayView<Vec3f> positions, ArrayView<Vec3f> normals, ArrayView<Rgb> colors,
             const ClusterOptions& options, std::size_t triangles) {
  s.positions = JoinedView<Vec3f>(positions, &s.added_positions);
  s.options = &options;
  s.threads = options.threads > 0 ? options.threads : int(std::max(1u, std::thread::hardware_concurrency()));
  s.weld = weld_positions(positions, s.threads);  // phase 1
  const float diagonal = bounds(positions).diagonal();
  s.input.positions = s.positions;
  s.input.normals = JoinedView<Vec3f>(normals, &s.added_normals);
  s.input.colors = JoinedView<Rgb>(colors, &s.added_colors);
  s.input.optimal_placement = options.optimal_placement;
  s.input.scale = diagonal > 0 ? 1.f / diagonal : 1.f;
  s.input.normal_weight = options.normal_weight;
  s.input.color_weight = options.color_weight;
  s.locked.assign(positions.size(), 0);
  s.input.locked = &s.locked;
  s.vertex_group.assign(positions.size(), -1);
  main.threads = s.threads;
  main.marks = &s.vertex_group;
  main.input = s.input;
  s.error_floor = 1e-7f * std::max(diagonal, 1e-30f);
  s.expected = 2.0 * double(triangles);
}

// What rank 0 sends the other ranks before a blocked build: the options
// that shape the hierarchy, and the sizes of the arrays that follow.
struct HierarchyStart {
  std::uint64_t blocked = 0;  // 0: no blocks to share, the others return
  std::uint64_t positions = 0, normals = 0, colors = 0, triangles = 0;
  std::int64_t block_triangles = 0;
  std::int32_t cluster_triangles = 0, group_clusters = 0, lanes = 0, optimal_placement = 0;
  double reduction = 0, first_reduction = 0, stall = 0;
  float normal_weight = 0, color_weight = 0;
};

template <class T>
void broadcast_array(WorkSharing& job, T* data, std::size_t count) {
  job.broadcast_from(0, static_cast<void*>(data), count * sizeof(T));
}

}  // namespace

void release_hierarchy_ranks(WorkSharing* job) {
  if (!job || job->ranks() == 1 || job->rank() != 0) return;
  HierarchyStart none;
  job->broadcast_from(0, &none, sizeof none);
}

void serve_cluster_hierarchy(WorkSharing& job, int threads) {
  HierarchyStart start;
  job.broadcast_from(0, &start, sizeof start);
  if (!start.blocked) return;
  std::vector<Vec3f> positions(start.positions), normals(start.normals);
  std::vector<Rgb> colors(start.colors);
  std::vector<Triangle> triangles(start.triangles);
  broadcast_array(job, positions.data(), positions.size());
  broadcast_array(job, normals.data(), normals.size());
  broadcast_array(job, colors.data(), colors.size());
  broadcast_array(job, triangles.data(), triangles.size());
  ClusterOptions options;
  options.cluster_triangles = start.cluster_triangles;
  options.group_clusters = start.group_clusters;
  options.reduction = start.reduction;
  options.first_reduction = start.first_reduction;
  options.stall = start.stall;
  options.normal_weight = start.normal_weight;
  options.color_weight = start.color_weight;
  options.optimal_placement = start.optimal_placement != 0;
  options.threads = threads;
  options.block_triangles = start.block_triangles;
  options.lanes = start.lanes;
  options.sharing = &job;
  Shared s;
  Lane main;
  prepare(s, main, positions, normals, colors, options, triangles.size());
  build_in_blocks(s, main, std::move(triangles), start.block_triangles);
}

ClusterHierarchy build_cluster_hierarchy(ArrayView<Vec3f> positions, ArrayView<Vec3f> normals,
                                         ArrayView<Rgb> colors, std::vector<Triangle> triangles,
                                         const ClusterOptions& options) {
  if (triangles.empty()) throw InputError("", "the cluster hierarchy needs a mesh with triangles, got none");
  for (const Triangle& t : triangles)
    for (std::int32_t v : t)
      if (v < 0 || std::size_t(v) >= positions.size())
        throw InputError("", "a triangle names vertex " + std::to_string(v) + " of " +
                                 std::to_string(positions.size()));
  Shared s;
  Lane main;
  prepare(s, main, positions, normals, colors, options, triangles.size());
  const std::int64_t blocked = block_triangles_for(options.block_triangles, triangles.size());
  if (WorkSharing* job = s.job()) {
    HierarchyStart start;
    start.blocked = blocked > 0;
    start.positions = positions.size(), start.normals = normals.size(), start.colors = colors.size();
    start.triangles = triangles.size();
    start.block_triangles = blocked;
    start.cluster_triangles = options.cluster_triangles, start.group_clusters = options.group_clusters;
    start.lanes = options.lanes, start.optimal_placement = options.optimal_placement;
    start.reduction = options.reduction, start.first_reduction = options.first_reduction, start.stall = options.stall;
    start.normal_weight = options.normal_weight, start.color_weight = options.color_weight;
    job->broadcast_from(0, &start, sizeof start);
    if (blocked) {
      broadcast_array(*job, const_cast<Vec3f*>(positions.data()), positions.size());
      broadcast_array(*job, const_cast<Vec3f*>(normals.data()), normals.size());
      broadcast_array(*job, const_cast<Rgb*>(colors.data()), colors.size());
      broadcast_array(*job, triangles.data(), triangles.size());
      s.stats.bytes_exchanged = double(positions.size() * sizeof(Vec3f) + normals.size() * sizeof(Vec3f) +
                                       colors.size() * sizeof(Rgb) + triangles.size() * sizeof(Triangle));
    }
  }

  ClusterHierarchy h;
  if (const std::int64_t block = blocked) {
    h = build_in_blocks(s, main, std::move(triangles), block);
  } else {
    // In core: the whole mesh is one block.
    Block all;
    all.h.full_triangles = std::int64_t(triangles.size());
    if (triangles.size() >= 2 * kSplitRun) {
      append_clusters(split_large_mesh(positions, triangles, options.cluster_triangles, s.threads), -1, 0, &all.h,
                      &all.active);
    } else {
      SplitGroup full;
      full.simplified.triangles = std::move(triangles);
      split_group(positions, options.cluster_triangles, &full);
      append_clusters(full, -1, 0, &all.h, &all.active);
    }
    triangles = std::vector<Triangle>();
    for (const Cluster& c : all.h.clusters)
      all.sphere.push_back(points_sphere(positions, &all.h.triangles[c.first_triangle], c.triangle_count));
    all.own_error.assign(all.h.clusters.size(), 0.f);
    all.own_rank.assign(all.h.clusters.size(), 0.f);
    all.seeds = all.h.clusters.size();
    run_rounds(s, main, &all, 255, true);
    h = std::move(all.h);
  }
  h.pages = cluster_pages(h);
  h.added_positions = std::move(s.added_positions);
  h.added_normals = std::move(s.added_normals);
  h.added_colors = std::move(s.added_colors);
  if (options.stats) *options.stats = s.stats;
  if (options.progress) options.progress(1.0);
  return h;
}

}  // namespace scan2lod
