#include <scan2lod/lod/clusters/group_clustering.h>

#include <scan2lod/core/point_triangle.h>
#include <scan2lod/core/union_find.h>
#include <scan2lod/lod/clusters/group_vertices.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace scan2lod {
namespace {

// Repairs of one cell size before it is given up: each splits at least one cell.
constexpr int kMaxRepairs = 200;
// Cell sizes tried, from this many mean edge lengths, growing by kGrowth.
constexpr double kFirstCell = 1.5, kGrowth = 1.6;
constexpr int kMaxSizes = 16;
constexpr std::uint64_t kSingleton = std::uint64_t(1) << 63;

// Squared distance to the planes of a vertex's triangles, area weighted:
// x^T A x + 2 b^T x + c with A symmetric (Garland and Heckbert, 1997).
struct PlaneQuadric {
  double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0, b0 = 0, b1 = 0, b2 = 0, c = 0;
  void add_plane(const Vec3d& n, double d, double w) {  // n unit, n.x + d = 0
    a00 += w * n.x() * n.x(), a01 += w * n.x() * n.y(), a02 += w * n.x() * n.z();
    a11 += w * n.y() * n.y(), a12 += w * n.y() * n.z(), a22 += w * n.z() * n.z();
    b0 += w * d * n.x(), b1 += w * d * n.y(), b2 += w * d * n.z(), c += w * d * d;
  }
  void add(const PlaneQuadric& o) {
    a00 += o.a00, a01 += o.a01, a02 += o.a02, a11 += o.a11, a12 += o.a12, a22 += o.a22;
    b0 += o.b0, b1 += o.b1, b2 += o.b2, c += o.c;
  }
  double evaluate(const Vec3d& p) const {
    const double x = p.x(), y = p.y(), z = p.z();
    return x * (a00 * x + 2 * a01 * y + 2 * a02 * z) + y * (a11 * y + 2 * a12 * z) + a22 * z * z +
           2 * (b0 * x + b1 * y + b2 * z) + c;
  }
};

// The group in local indices, and what every clustering of it checks against.
struct Group {
  std::vector<std::int32_t> global;           // local -> welded global vertex
  std::vector<Vec3d> p;
  std::vector<std::array<std::int32_t, 3>> tris;
  std::vector<Vec3d> tri_normal;              // unnormalized
  std::vector<std::uint8_t> fixed;            // locked, on the real boundary, or complex
  std::vector<std::uint8_t> locked;           // shared with another group
  std::vector<std::int32_t> piece;            // connected piece of each vertex
  std::vector<std::uint64_t> edges;           // every input edge's key, sorted
  std::vector<std::uint64_t> boundary_edges;  // used once, sorted
  std::vector<PlaneQuadric> quadric;
  double mean_edge = 0;
  Aabb box;
};

std::uint64_t key_of(std::int32_t a, std::int32_t b) { return edge_key(a, b); }

bool contains(const std::vector<std::uint64_t>& sorted, std::uint64_t key) {
  return std::binary_search(sorted.begin(), sorted.end(), key);
}

// Phase 1: local indices, pieces, edges and the vertices clustering must not move.
void load(const std::vector<Triangle>& triangles, const SimplifyInput& in, ClusterSoundness soundness,
          Group* g) {
  thread_local GroupVertices local;
  local.clear();
  for (const Triangle& t : triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    g->tris.push_back({local.local(t[0]), local.local(t[1]), local.local(t[2])});
  }
  g->global = local.global();
  const std::size_t nv = g->global.size();
  g->p.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    g->p[v] = in.positions[std::size_t(g->global[v])].cast<double>();
    g->box.extend(in.positions[std::size_t(g->global[v])]);
  }
  g->locked.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) g->locked[v] = (*in.locked)[std::size_t(g->global[v])] != 0;
  g->fixed = g->locked;

  std::vector<std::pair<std::uint64_t, int>> directed;
  directed.reserve(3 * g->tris.size());
  UnionFind pieces(nv);
  g->quadric.assign(nv, PlaneQuadric());
  g->tri_normal.resize(g->tris.size());
  double length = 0;
  for (std::size_t t = 0; t < g->tris.size(); ++t) {
    const auto& x = g->tris[t];
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = x[std::size_t(k)], b = x[std::size_t((k + 1) % 3)];
      directed.push_back({key_of(a, b), a < b ? 1 : -1});
      pieces.unite(a, b);
      length += (g->p[std::size_t(a)] - g->p[std::size_t(b)]).norm();
    }
    const Vec3d n = (g->p[std::size_t(x[1])] - g->p[std::size_t(x[0])]).cross(g->p[std::size_t(x[2])] - g->p[std::size_t(x[0])]);
    g->tri_normal[t] = n;
    const double area2 = n.norm();
    if (!(area2 > 0)) continue;
    const Vec3d unit = n / area2;
    for (std::int32_t v : x) g->quadric[std::size_t(v)].add_plane(unit, -unit.dot(g->p[std::size_t(x[0])]), 0.5 * area2);
  }
  g->mean_edge = g->tris.empty() ? 0 : length / double(3 * g->tris.size());
  g->piece.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) g->piece[v] = pieces.find(std::int32_t(v));

  std::sort(directed.begin(), directed.end());
  for (std::size_t i = 0; i < directed.size();) {
    std::size_t j = i;
    int orientation = 0;
    while (j < directed.size() && directed[j].first == directed[i].first) orientation += directed[j].second, ++j;
    const std::uint64_t key = directed[i].first;
    const std::size_t a = std::size_t(key >> 32), b = std::size_t(key & 0xffffffffu);
    g->edges.push_back(key);
    if (j - i == 1) g->boundary_edges.push_back(key);
    // A manifold clustering keeps the real boundary and what is complex already.
    if (soundness == ClusterSoundness::kManifold && (j - i == 1 || j - i > 2 || orientation != 0))
      g->fixed[a] = g->fixed[b] = 1;
    i = j;
  }
}

// One clustering: each vertex's cell and representative, and the triangles
// that survive.
struct Clustering {
  std::vector<std::int32_t> rep;                    // per vertex
  std::vector<std::uint8_t> split;                  // per vertex: its cell was split back
  std::vector<std::pair<std::uint64_t, std::int32_t>> cells;  // (cell key, vertex), sorted
  std::vector<std::array<std::int32_t, 3>> out;     // in local indices
  std::vector<std::int32_t> source;                 // input triangle of each output triangle
};

// Phase 2: cells of size h (split cells and fixed vertices alone), each
// drawn to the member whose position its summed quadric likes best.
void cluster(const Group& g, double h, Clustering* c) {
  const std::size_t nv = g.p.size();
  c->cells.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    std::uint64_t key = kSingleton | v;
    if (!g.fixed[v] && !c->split[v]) {
      const Vec3d q = (g.p[v] - g.box.min.cast<double>()) / h;
      key = std::uint64_t(q.x()) << 42 | std::uint64_t(q.y()) << 21 | std::uint64_t(q.z());
    }
    c->cells[v] = {key, std::int32_t(v)};
  }
  // A cell is the vertices of one grid cube joined by edges inside it: two
  // sheets that pass through one cube do not merge, while a tube thinner than
  // the cube, whose ring of edges lies inside it, does.
  UnionFind joined(nv);
  for (const std::uint64_t e : g.edges) {
    const std::int32_t a = std::int32_t(e >> 32), b = std::int32_t(e & 0xffffffffu);
    if (c->cells[std::size_t(a)].first == c->cells[std::size_t(b)].first && !(c->cells[std::size_t(a)].first & kSingleton))
      joined.unite(a, b);
  }
  for (std::size_t v = 0; v < nv; ++v)
    if (!(c->cells[v].first & kSingleton)) c->cells[v].first = std::uint64_t(joined.find(std::int32_t(v)));
  std::sort(c->cells.begin(), c->cells.end());
  c->rep.resize(nv);
  for (std::size_t i = 0; i < nv;) {
    std::size_t j = i;
    PlaneQuadric sum;
    while (j < nv && c->cells[j].first == c->cells[i].first) sum.add(g.quadric[std::size_t(c->cells[j].second)]), ++j;
    std::int32_t best = c->cells[i].second;
    double best_cost = std::numeric_limits<double>::infinity();
    for (std::size_t k = i; k < j && j - i > 1; ++k) {
      const double cost = sum.evaluate(g.p[std::size_t(c->cells[k].second)]);
      if (cost < best_cost) best_cost = cost, best = c->cells[k].second;
    }
    for (std::size_t k = i; k < j; ++k) c->rep[std::size_t(c->cells[k].second)] = best;
    i = j;
  }
  // Triangles on their representatives; a pair on the same corners facing
  // away from each other is a sheet pressed flat, and goes.
  struct Mapped {
    std::array<std::int32_t, 3> sorted;
    int parity;
    std::int32_t source;
    bool operator<(const Mapped& o) const { return sorted < o.sorted || (sorted == o.sorted && source < o.source); }
  };
  thread_local std::vector<Mapped> mapped;
  mapped.clear();
  for (std::size_t t = 0; t < g.tris.size(); ++t) {
    std::array<std::int32_t, 3> r;
    for (int k = 0; k < 3; ++k) r[std::size_t(k)] = c->rep[std::size_t(g.tris[t][std::size_t(k)])];
    if (r[0] == r[1] || r[1] == r[2] || r[0] == r[2]) continue;
    // Rotated so the smallest leads: then the orientation is whether the
    // other two ascend.
    std::rotate(r.begin(), std::min_element(r.begin(), r.end()), r.end());
    const int parity = r[1] < r[2] ? 1 : -1;
    std::array<std::int32_t, 3> s = r;
    if (parity < 0) std::swap(s[1], s[2]);
    mapped.push_back({s, parity, std::int32_t(t)});
  }
  std::sort(mapped.begin(), mapped.end());
  c->out.clear();
  c->source.clear();
  for (std::size_t i = 0; i < mapped.size();) {
    std::size_t j = i;
    int sum = 0;
    while (j < mapped.size() && mapped[j].sorted == mapped[i].sorted) sum += mapped[j].parity, ++j;
    // Opposite pairs cancel; what is left keeps one triangle per
    // orientation still present, and the checks judge a doubled one.
    const std::size_t keep = std::size_t(std::abs(sum)) + (sum == 0 && (j - i) % 2 == 1 ? 1 : 0);
    for (std::size_t k = 0; k < keep; ++k) {
      const Mapped& m = mapped[i];
      const int parity = sum != 0 ? (sum > 0 ? 1 : -1) : m.parity;
      std::array<std::int32_t, 3> t = m.sorted;
      if (parity < 0) std::swap(t[1], t[2]);
      c->out.push_back(t);
      std::int32_t src = m.source;
      for (std::size_t q = i; q < j; ++q)
        if (mapped[q].parity == parity) src = mapped[q].source;
      c->source.push_back(src);
    }
    i = j;
  }
}

// Phase 3: what breaks soundness, as the vertices whose cells must split:
// for each break, the cells of the vertices at it that hold more than one
// vertex, or failing those the cells of their neighbours. Empty when the
// clustering is sound, or when what is left was in the input already.
void violations(const Group& g, const Clustering& c, ClusterSoundness soundness, std::vector<std::int32_t>* bad) {
  bad->clear();
  thread_local std::vector<std::int32_t> members;
  members.assign(c.rep.size(), 0);
  for (std::int32_t r : c.rep) ++members[std::size_t(r)];
  auto merged = [&](std::int32_t v) { return members[std::size_t(c.rep[std::size_t(v)])] > 1; };
  // Blames the merged ones of `primary`, else those of `secondary`.
  thread_local std::vector<std::int32_t> primary, secondary;
  auto blame = [&] {
    bool any = false;
    for (std::int32_t v : primary)
      if (merged(v)) bad->push_back(v), any = true;
    if (!any)
      for (std::int32_t v : secondary)
        if (merged(v)) bad->push_back(v);
    primary.clear();
    secondary.clear();
  };
  auto corners = [&](std::size_t t, std::vector<std::int32_t>* to) { to->insert(to->end(), c.out[t].begin(), c.out[t].end()); };
  // Edges: on two triangles facing opposite ways, or on one where the input
  // had a boundary; none new between two locked vertices.
  thread_local std::vector<std::pair<std::uint64_t, std::int32_t>> edges;  // (key, triangle * 2 + forward)
  edges.clear();
  for (std::size_t t = 0; t < c.out.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = c.out[t][std::size_t(k)], b = c.out[t][std::size_t((k + 1) % 3)];
      edges.push_back({key_of(a, b), std::int32_t(2 * t + (a < b ? 1 : 0))});
    }
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    int forward = 0;
    while (j < edges.size() && edges[j].first == edges[i].first) forward += edges[j].second & 1, ++j;
    const std::uint64_t key = edges[i].first;
    const std::size_t n = j - i;
    const std::int32_t a = std::int32_t(key >> 32), b = std::int32_t(key & 0xffffffffu);
    const bool sound = soundness == ClusterSoundness::kPiecesOnly || (n == 2 && forward == 1) ||
                       (n == 1 && contains(g.boundary_edges, key));
    const bool new_locked = g.locked[std::size_t(a)] && g.locked[std::size_t(b)] && !contains(g.edges, key);
    if (!sound || new_locked) {
      primary = {a, b};
      for (std::size_t k = i; k < j; ++k) corners(std::size_t(edges[k].second >> 1), &secondary);
      blame();
    }
    i = j;
  }
  // Triangles turned over against the one they came from.
  for (std::size_t t = 0; t < c.out.size() && soundness == ClusterSoundness::kManifold; ++t) {
    const auto& x = c.out[t];
    const Vec3d n = (g.p[std::size_t(x[1])] - g.p[std::size_t(x[0])]).cross(g.p[std::size_t(x[2])] - g.p[std::size_t(x[0])]);
    const Vec3d& before = g.tri_normal[std::size_t(c.source[t])];
    if (!(n.dot(before) > 0.1 * n.norm() * before.norm())) {
      corners(t, &primary);
      blame();
    }
  }
  // Vertices whose triangles are not one fan: their link, the edges opposite
  // them, must be one chain or one cycle.
  thread_local std::vector<std::pair<std::int32_t, std::int32_t>> around;  // (vertex, triangle)
  around.clear();
  for (std::size_t t = 0; t < c.out.size(); ++t)
    for (std::int32_t v : c.out[t]) around.push_back({v, std::int32_t(t)});
  std::sort(around.begin(), around.end());
  thread_local std::vector<std::pair<std::int32_t, std::int32_t>> link;
  for (std::size_t i = 0; i < around.size() && soundness == ClusterSoundness::kManifold;) {
    std::size_t j = i;
    while (j < around.size() && around[j].first == around[i].first) ++j;
    const std::int32_t v = around[i].first;
    link.clear();
    for (std::size_t k = i; k < j; ++k) {
      const auto& x = c.out[std::size_t(around[k].second)];
      const int at = x[0] == v ? 0 : x[1] == v ? 1 : 2;
      link.push_back({x[std::size_t((at + 1) % 3)], x[std::size_t((at + 2) % 3)]});
    }
    std::sort(link.begin(), link.end());
    bool fan = true;
    for (std::size_t k = 1; k < link.size(); ++k) fan &= link[k].first != link[k - 1].first;
    std::int32_t start = -1;
    int starts = 0;
    for (const auto& e : link) {
      bool entered = false;
      for (const auto& f : link) entered |= f.second == e.first;
      if (!entered) start = e.first, ++starts;
    }
    if (fan && starts <= 1) {
      // Walk the chain (or the cycle from its first edge): it must take every edge.
      std::int32_t at = starts == 1 ? start : link[0].first;
      std::size_t steps = 0;
      for (; steps <= link.size(); ++steps) {
        auto it = std::lower_bound(link.begin(), link.end(), std::make_pair(at, std::numeric_limits<std::int32_t>::min()));
        if (it == link.end() || it->first != at) break;
        at = it->second;
        if (starts == 0 && at == link[0].first) {
          ++steps;
          break;
        }
      }
      fan = steps == link.size();
    }
    if (!fan) {
      primary = {v};
      for (std::size_t k = i; k < j; ++k) corners(std::size_t(around[k].second), &secondary);
      blame();
    }
    i = j;
  }
  // Pieces: none may vanish.
  thread_local std::vector<std::uint8_t> kept;
  kept.assign(g.p.size(), 0);
  for (const auto& x : c.out)
    for (std::int32_t v : x) kept[std::size_t(g.piece[std::size_t(v)])] = 1;
  for (std::size_t v = 0; v < g.p.size(); ++v)
    if (!kept[std::size_t(g.piece[v])] && merged(std::int32_t(v))) bad->push_back(std::int32_t(v));
}

// Splits the cells of `bad` back into their vertices.
void split_cells(const std::vector<std::int32_t>& bad, Clustering* c) {
  thread_local std::vector<std::uint8_t> blamed;
  blamed.assign(c->rep.size(), 0);
  for (std::int32_t v : bad) blamed[std::size_t(c->rep[std::size_t(v)])] = 1;
  for (std::size_t v = 0; v < c->rep.size(); ++v)
    if (blamed[std::size_t(c->rep[v])]) c->split[v] = 1;
}

// Phase 4: the measured error, as the collapse's: how far each vertex lies
// from the triangles around its representative (from every triangle where
// its whole cell vanished), the largest and the mean.
struct MeasuredError {
  double largest = 0, mean = 0;
};
MeasuredError cluster_error(const Group& g, const Clustering& c) {
  std::vector<std::int32_t> first(g.p.size() + 1, 0);
  for (const auto& x : c.out)
    for (std::int32_t v : x) ++first[std::size_t(v) + 1];
  for (std::size_t v = 0; v < g.p.size(); ++v) first[v + 1] += first[v];
  std::vector<std::int32_t> incident(std::size_t(first.back()));
  {
    std::vector<std::int32_t> fill(first.begin(), first.end() - 1);
    for (std::size_t t = 0; t < c.out.size(); ++t)
      for (std::int32_t v : c.out[t]) incident[std::size_t(fill[std::size_t(v)]++)] = std::int32_t(t);
  }
  auto distance2 = [&](const Vec3d& q, std::size_t t) {
    const auto& x = c.out[t];
    return point_triangle_distance2(q, g.p[std::size_t(x[0])], g.p[std::size_t(x[1])], g.p[std::size_t(x[2])]);
  };
  MeasuredError e;
  std::size_t count = 0;
  for (std::size_t v = 0; v < g.p.size(); ++v) {
    const std::size_t r = std::size_t(c.rep[v]);
    if (r == v && first[r + 1] > first[r]) continue;
    double nearest = std::numeric_limits<double>::infinity();
    for (std::int32_t i = first[r]; i < first[r + 1]; ++i) nearest = std::min(nearest, distance2(g.p[v], std::size_t(incident[std::size_t(i)])));
    if (first[r + 1] == first[r])
      for (std::size_t t = 0; t < c.out.size(); ++t) nearest = std::min(nearest, distance2(g.p[v], t));
    if (!std::isfinite(nearest)) continue;
    nearest = std::sqrt(nearest);
    e.largest = std::max(e.largest, nearest), e.mean += nearest, ++count;
  }
  if (count > 0) e.mean /= double(count);
  return e;
}

}  // namespace

SimplifiedGroup cluster_group(const std::vector<Triangle>& triangles, std::size_t target, const SimplifyInput& in,
                              ClusterSoundness soundness) {
  Group g;
  load(triangles, in, soundness, &g);
  SimplifiedGroup best;
  best.triangles = triangles;
  if (g.tris.empty() || !(g.mean_edge > 0)) return best;

  Clustering c, best_clustering;
  std::vector<std::int32_t> bad;
  std::size_t best_count = g.tris.size();
  const double largest = double(g.box.diagonal());
  double h = kFirstCell * g.mean_edge;
  for (int size = 0; size < kMaxSizes && h < 2 * largest; ++size, h *= kGrowth) {
    c.split.assign(g.p.size(), 0);
    bool sound = false;
    for (int repair = 0; repair <= kMaxRepairs; ++repair) {
      cluster(g, h, &c);
      violations(g, c, soundness, &bad);
      if (bad.empty()) {
        sound = true;
        break;
      }
      split_cells(bad, &c);
    }
    if (!sound || c.out.size() >= best_count) continue;
    best_count = c.out.size();
    best_clustering = c;
    if (best_count <= target) break;
  }
  if (best_count == g.tris.size()) return best;
  best.triangles.clear();
  for (const auto& x : best_clustering.out)
    best.triangles.push_back({g.global[std::size_t(x[0])], g.global[std::size_t(x[1])], g.global[std::size_t(x[2])]});
  const MeasuredError e = cluster_error(g, best_clustering);
  best.error = float(e.largest);
  best.mean_error = float(e.mean);
  return best;
}

}  // namespace scan2lod
