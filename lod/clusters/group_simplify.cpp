#include <scan2lod/lod/clusters/group_simplify.h>

#include <scan2lod/core/point_triangle.h>
#include <scan2lod/lod/clusters/group_vertices.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <queue>

namespace scan2lod {
namespace {

constexpr int kMaxDim = 9;                   // position, normal, colour
// A pivot below this share of the largest diagonal entry is a direction the
// quadric does not constrain.
constexpr double kSingular = 1e-9;
// Boundary constraint planes weigh this much per unit of squared edge length,
// against the faces' area: a real boundary then moves along itself, not inwards.
constexpr double kBoundaryWeight = 4.0;

// x^T A x + 2 b^T x + c over the first `dim` coordinates, packed for that
// dimension: A's upper triangle row by row, then b, then c. Sums of squared
// distances to planes in R^dim. (Packed, a 6-dimensional quadric is 28
// doubles, not the 55 of the largest: adding them was a tenth of the
// instructions of a whole-mesh build.) The functions work on a quadric's
// doubles where they are: a group's quadrics are one flat array.
struct Quadric {
  static constexpr int size(int dim) { return upper(dim) + dim + 1; }
  static constexpr int upper(int dim) { return dim * (dim + 1) / 2; }
  static constexpr int row(int i, int dim) { return i * dim - i * (i - 1) / 2; }  // where A's row i starts

  // Each operation dispatches to a version of fixed dimension (3, 6 or 9),
  // whose loops of a known length unroll: the quadrics' set-up fell from 9 %
  // to 8 % of a build's instructions. Same operations, same order.
  static void add(double* v, const double* o, int dim) {
    switch (dim) {
      case 3: return add_fixed<3>(v, o);
      case 6: return add_fixed<6>(v, o);
      default: return add_fixed<9>(v, o);
    }
  }
  static double evaluate(const double* v, const double* x, int dim) {
    switch (dim) {
      case 3: return evaluate_fixed<3>(v, x);
      case 6: return evaluate_fixed<6>(v, x);
      default: return evaluate_fixed<9>(v, x);
    }
  }
  // Adds w * (I - e0 e0^T - e1 e1^T) for the orthonormal basis {e0, e1} of
  // a plane through q, over the first `plane_dim` (3 or all) of the
  // quadric's `dim` coordinates.
  static void add_plane(double* v, const double* q, const double (*basis)[kMaxDim], int plane_dim, int dim, double w) {
    switch (dim * 16 + plane_dim) {
      case 3 * 16 + 3: return add_plane_fixed<3, 3>(v, q, basis, w);
      case 6 * 16 + 3: return add_plane_fixed<3, 6>(v, q, basis, w);
      case 6 * 16 + 6: return add_plane_fixed<6, 6>(v, q, basis, w);
      case 9 * 16 + 3: return add_plane_fixed<3, 9>(v, q, basis, w);
      default: return add_plane_fixed<9, 9>(v, q, basis, w);
    }
  }

 private:
  template <int D>
  static void add_fixed(double* v, const double* o) {
    for (int i = 0; i < size(D); ++i) v[i] += o[i];
  }
  template <int D>
  static double evaluate_fixed(const double* v, const double* x) {
    constexpr int n = upper(D);
    double e = v[std::size_t(n + D)];
    int k = 0;
    for (int i = 0; i < D; ++i) {
      double r = v[std::size_t(k++)] * x[i];
      for (int j = i + 1; j < D; ++j) r += 2 * v[std::size_t(k++)] * x[j];
      e += x[i] * r + 2 * v[std::size_t(n + i)] * x[i];
    }
    return e;
  }
  template <int PD, int D>
  static void add_plane_fixed(double* v, const double* q, const double (*basis)[kMaxDim], double w) {
    constexpr int n = upper(D);
    double qe[2] = {0, 0};
    for (int s = 0; s < 2; ++s)
#pragma GCC unroll 9
      for (int i = 0; i < PD; ++i) qe[s] += q[i] * basis[s][i];
#pragma GCC unroll 9
    for (int i = 0; i < PD; ++i) {
      int k = row(i, D);
#pragma GCC unroll 9
      for (int j = i; j < PD; ++j) {
        double a = i == j ? 1.0 : 0.0;
        for (int s = 0; s < 2; ++s) a -= basis[s][i] * basis[s][j];
        v[std::size_t(k++)] += w * a;
      }
      double bi = -q[i];
      for (int s = 0; s < 2; ++s) bi += qe[s] * basis[s][i];
      v[std::size_t(n + i)] += w * bi;
    }
    double qq = 0;
    for (int i = 0; i < PD; ++i) qq += q[i] * q[i];
    for (int s = 0; s < 2; ++s) qq -= qe[s] * qe[s];
    v[std::size_t(n + D)] += w * qq;
  }
};

// Where p + q is least (A x = -b), into `out`, with the value there; false
// where A is near singular (a flat or straight neighbourhood, where any
// point along it is as good and the solve would wander). LDL^T by hand and
// of a fixed size: Eigen's with its condition estimate took half the
// hierarchy's build, and a loop over the dimension a quarter.
template <int D>
bool sum_minimum(const double* p, const double* q, double* out, double* value) {
  constexpr int n = D * (D + 1) / 2;  // where b starts
  double s[n + D + 1];                // p + q, packed as they are
  for (int i = 0; i < n + D + 1; ++i) s[i] = p[i] + q[i];
  double m[D][D], y[D];
  double largest = 0;
  // Unrolled whole: as loops, the indexing was half the solve's instructions.
#pragma GCC unroll 9
  for (int i = 0; i < D; ++i) {
    const int row = Quadric::row(i, D);
#pragma GCC unroll 9
    for (int j = i; j < D; ++j) m[j][i] = s[row + j - i];
    largest = std::max(largest, std::abs(m[i][i]));
  }
  if (!(largest > 0)) return false;
#pragma GCC unroll 9
  for (int j = 0; j < D; ++j) {  // lower triangle: L below, D on the diagonal
    double ld[D];                 // row j of L times D, taken once for the column
    double d = m[j][j];
#pragma GCC unroll 9
    for (int k = 0; k < j; ++k) ld[k] = m[j][k] * m[k][k], d -= m[j][k] * ld[k];
    if (!(d > kSingular * largest)) return false;
    m[j][j] = d;
    const double inverse = 1 / d;
#pragma GCC unroll 9
    for (int i = j + 1; i < D; ++i) {
      double v = m[i][j];
#pragma GCC unroll 9
      for (int k = 0; k < j; ++k) v -= m[i][k] * ld[k];
      m[i][j] = v * inverse;
    }
  }
#pragma GCC unroll 9
  for (int i = 0; i < D; ++i) {
    double v = -s[n + i];
#pragma GCC unroll 9
    for (int k = 0; k < i; ++k) v -= m[i][k] * y[k];
    y[i] = v;
  }
#pragma GCC unroll 9
  for (int i = 0; i < D; ++i) y[i] /= m[i][i];
  double at = s[n + D];  // x^T A x + 2 b^T x + c where A x = -b
#pragma GCC unroll 9
  for (int i = D - 1; i >= 0; --i) {
    double v = y[i];
#pragma GCC unroll 9
    for (int k = i + 1; k < D; ++k) v -= m[k][i] * out[k];
    if (!std::isfinite(v)) return false;
    out[i] = v;
  }
#pragma GCC unroll 9
  for (int i = 0; i < D; ++i) at += s[n + i] * out[i];
  *value = at;
  return true;
}

bool sum_minimum(int dim, const double* p, const double* q, double* out, double* value) {
  switch (dim) {
    case 3: return sum_minimum<3>(p, q, out, value);
    case 6: return sum_minimum<6>(p, q, out, value);
    case 9: return sum_minimum<9>(p, q, out, value);
    default: return false;  // no other dimension is built
  }
}

struct GroupQuadrics {
  int dim = 3;
  double scale = 1;                            // x's positions over the stored ones
  std::vector<std::array<double, kMaxDim>> x;  // each vertex's point in R^dim
  std::vector<double> full;  // each vertex's quadric (position + attributes), Quadric::size(dim) doubles

  double* quadric(std::size_t v) { return full.data() + v * std::size_t(Quadric::size(dim)); }
  const double* quadric(std::size_t v) const { return full.data() + v * std::size_t(Quadric::size(dim)); }
};

// Orthonormal basis of the plane through p0, p1, p2 in R^dim (Gram-Schmidt);
// false for a degenerate triangle.
bool triangle_basis(const double* p0, const double* p1, const double* p2, int dim, double (*e)[kMaxDim]) {
  double n1 = 0, d = 0, n2 = 0;
  for (int i = 0; i < dim; ++i) e[0][i] = p1[i] - p0[i], n1 += e[0][i] * e[0][i];
  if (!(n1 > 1e-30)) return false;
  n1 = std::sqrt(n1);
  for (int i = 0; i < dim; ++i) e[0][i] /= n1;
  for (int i = 0; i < dim; ++i) d += (p2[i] - p0[i]) * e[0][i];
  for (int i = 0; i < dim; ++i) e[1][i] = p2[i] - p0[i] - d * e[0][i], n2 += e[1][i] * e[1][i];
  if (!(n2 > 1e-30)) return false;
  n2 = std::sqrt(n2);
  for (int i = 0; i < dim; ++i) e[1][i] /= n2;
  return true;
}


// The group in local indices, with each vertex's triangles.
struct GroupTopology {
  std::vector<std::array<int, 3>> tris;
  std::vector<std::uint8_t> dead;           // per triangle
  std::vector<std::vector<int>> incident;   // per vertex: its live triangles (and some dead ones)
  std::vector<std::uint8_t> locked, border; // per vertex
  std::vector<std::uint8_t> mark;           // scratch per vertex
};

int other_count(const GroupTopology& g, int t, int a, int b) {
  const auto& x = g.tris[std::size_t(t)];
  return (x[0] == a || x[1] == a || x[2] == a) && (x[0] == b || x[1] == b || x[2] == b);
}

// Phase: classify. An edge used once is on a border (the scan's real boundary,
// since group borders are locked anyway); used more than twice, or a vertex
// whose border is not one simple chain, is complex and stays where it is.
void classify(GroupTopology* g) {
  // Each edge counted from its smaller end, over that end's triangles: a
  // sort of all edges was 1.6 % of a whole build's instructions.
  const std::size_t nv = g->border.size();  // incident is kept from larger groups
  std::vector<int> border_edges(nv, 0);
  thread_local std::vector<int> uses, orientation, around;
  uses.assign(nv, 0), orientation.assign(nv, 0);
  for (std::size_t v = 0; v < nv; ++v) {
    around.clear();
    for (int t : g->incident[v]) {
      const auto& tri = g->tris[std::size_t(t)];
      for (int k = 0; k < 3; ++k) {
        if (tri[std::size_t(k)] != int(v)) continue;
        const int next = tri[std::size_t((k + 1) % 3)], previous = tri[std::size_t((k + 2) % 3)];
        for (const auto& [w, sign] : {std::pair<int, int>{next, 1}, std::pair<int, int>{previous, -1}}) {
          if (w <= int(v)) continue;
          if (uses[std::size_t(w)]++ == 0) around.push_back(w);
          orientation[std::size_t(w)] += sign;
        }
      }
    }
    for (int w : around) {
      const int n = uses[std::size_t(w)];
      if (n == 1) {
        ++border_edges[v], ++border_edges[std::size_t(w)];
      } else if (n > 2 || orientation[std::size_t(w)] != 0) {
        g->locked[v] = g->locked[std::size_t(w)] = 1;  // non-manifold or flipped neighbours
      }
      uses[std::size_t(w)] = 0, orientation[std::size_t(w)] = 0;
    }
  }
  for (std::size_t v = 0; v < nv; ++v) {
    if (border_edges[v] > 2) g->locked[v] = 1;  // two border chains meet here
    g->border[v] = border_edges[v] > 0;
  }
}

struct Candidate {
  float cost;
  int from, to;
  std::uint32_t from_version, to_version;  // of the quadrics its cost was computed from
  bool operator>(const Candidate& o) const { return cost > o.cost; }
};

// Phase: may `from` and `to` merge into one vertex at `target`? Border
// vertices only slide along their border; the edge's link must be its one or
// two opposite vertices (no fold into a non-manifold); no triangle may turn
// over or collapse; and no new edge may join two locked vertices, which a
// neighbouring group might join too.
bool collapse_allowed(GroupTopology* g, int from, int to, const Eigen::Vector3d& target,
                      const std::vector<std::array<double, kMaxDim>>& x, double scale) {
  if (g->locked[std::size_t(from)]) return false;
  int shared = 0;
  for (int t : g->incident[std::size_t(from)])
    if (!g->dead[std::size_t(t)] && other_count(*g, t, from, to)) ++shared;
  if (shared == 0) return false;
  if (g->border[std::size_t(from)] && !(g->border[std::size_t(to)] && shared == 1)) return false;

  // Link condition: the vertices next to both are exactly the opposite ones.
  for (int t : g->incident[std::size_t(to)])
    if (!g->dead[std::size_t(t)])
      for (int v : g->tris[std::size_t(t)]) g->mark[std::size_t(v)] = 1;
  int common = 0;
  bool locked_edge = false;
  for (int t : g->incident[std::size_t(from)]) {
    if (g->dead[std::size_t(t)]) continue;
    for (int v : g->tris[std::size_t(t)]) {
      if (v == from || v == to) continue;
      if (g->mark[std::size_t(v)] == 1) g->mark[std::size_t(v)] = 2, ++common;
      else if (g->mark[std::size_t(v)] == 0 && g->locked[std::size_t(v)] && g->locked[std::size_t(to)]) locked_edge = true;
    }
  }
  for (int t : g->incident[std::size_t(to)])
    if (!g->dead[std::size_t(t)])
      for (int v : g->tris[std::size_t(t)]) g->mark[std::size_t(v)] = 0;
  if (common != shared || locked_edge) return false;

  // Each triangle the collapse removes keeps its third vertex tied to the
  // kept one through another triangle. Where it is the only tie (a triangle
  // hanging on the border by one corner) the collapse would cut a piece off:
  // on scans with open boundaries that left pieces of 1-3 triangles.
  for (int t : g->incident[std::size_t(from)]) {
    if (g->dead[std::size_t(t)] || !other_count(*g, t, from, to)) continue;
    for (int w : g->tris[std::size_t(t)]) {
      if (w == from || w == to) continue;
      bool tied = false;
      for (int u : g->incident[std::size_t(w)]) {
        if (g->dead[std::size_t(u)] || other_count(*g, u, from, to)) continue;
        const auto& x = g->tris[std::size_t(u)];
        tied |= x[0] == from || x[1] == from || x[2] == from || x[0] == to || x[1] == to || x[2] == to;
      }
      if (!tied) return false;
    }
  }

  // No triangle around either turns over or becomes a sliver.
  for (const int end : {from, to})
  for (int t : g->incident[std::size_t(end)]) {
    if (g->dead[std::size_t(t)] || other_count(*g, t, from, to)) continue;
    const auto& tri = g->tris[std::size_t(t)];
    Eigen::Vector3d p[3], q[3];
    for (int k = 0; k < 3; ++k) {
      const auto& xv = x[std::size_t(tri[std::size_t(k)])];
      p[k] = Eigen::Vector3d(xv[0], xv[1], xv[2]);
      q[k] = tri[std::size_t(k)] == from || tri[std::size_t(k)] == to ? target : p[k];
    }
    const Eigen::Vector3d before = (p[1] - p[0]).cross(p[2] - p[0]), after = (q[1] - q[0]).cross(q[2] - q[0]);
    const double a = after.norm();
    // In line as the stored float positions have it: a vertex placed a hair
    // off a box's flat face rounds back onto it, in line with two others.
    const auto stored = [&](const Eigen::Vector3d& v) { return Vec3f((v / scale).cast<float>()); };
    if (!(a > 0) || in_line(stored(q[0]), stored(q[1]), stored(q[2])) ||
        after.dot(before) < 0.2 * before.norm() * a)
      return false;
  }
  return true;
}

}  // namespace

// Phase 1: the group's triangles in local indices, with their incidence and
// which vertices are locked or on the border. Returns local -> global.
std::vector<std::int32_t> load_group(const std::vector<Triangle>& triangles, const SimplifyInput& in,
                                     GroupTopology* group) {
  GroupTopology& g = *group;
  g.tris.clear();
  thread_local GroupVertices local;
  local.clear();
  for (const Triangle& t : triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    g.tris.push_back({local.local(t[0]), local.local(t[1]), local.local(t[2])});
  }
  std::vector<std::int32_t> global = local.global();
  const std::size_t nv = global.size();
  g.dead.assign(g.tris.size(), 0);
  if (g.incident.size() < nv) g.incident.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) g.incident[v].clear();
  for (std::size_t t = 0; t < g.tris.size(); ++t)
    for (int v : g.tris[t]) g.incident[std::size_t(v)].push_back(int(t));
  g.locked.assign(nv, 0);
  g.border.assign(nv, 0);
  g.mark.assign(nv, 0);
  if (in.locked)
    for (std::size_t v = 0; v < nv; ++v) g.locked[v] = (*in.locked)[std::size_t(global[v])];
  classify(&g);

  return global;
}

// Phase 2: each vertex's generalized quadric (position, and normal and colour
// when weighted), with border planes so that borders slide along themselves.
void group_quadrics(const GroupTopology& g, const std::vector<std::int32_t>& global, const SimplifyInput& in,
                    bool use_normals, bool use_colors, GroupQuadrics* quadrics) {
  const JoinedView<Vec3f>& positions = in.positions;
  GroupQuadrics& q = *quadrics;
  const std::size_t nv = global.size();
  q.dim = 3 + (use_normals ? 3 : 0) + (use_colors ? 3 : 0);
  q.scale = in.scale;
  q.x.resize(nv);
  q.full.assign(nv * std::size_t(Quadric::size(q.dim)), 0.0);
  for (std::size_t v = 0; v < nv; ++v) {
    const std::size_t gv = std::size_t(global[v]);
    double* x = q.x[v].data();
    int d = 0;
    for (int i = 0; i < 3; ++i) x[d++] = double(positions[gv][i]) * in.scale;
    if (use_normals)
      for (int i = 0; i < 3; ++i) x[d++] = double(in.normals[gv][i]) * in.normal_weight;
    if (use_colors)
      for (int i = 0; i < 3; ++i) x[d++] = double(in.colors[gv][std::size_t(i)]) / 255.0 * in.color_weight;
  }
  for (const auto& tri : g.tris) {
    const double* p[3] = {q.x[std::size_t(tri[0])].data(), q.x[std::size_t(tri[1])].data(), q.x[std::size_t(tri[2])].data()};
    const Eigen::Vector3d a(p[0][0], p[0][1], p[0][2]), b(p[1][0], p[1][1], p[1][2]), c(p[2][0], p[2][1], p[2][2]);
    const Eigen::Vector3d normal = (b - a).cross(c - a);
    const double area = 0.5 * normal.norm();
    if (!(area > 0)) continue;
    double basis[2][kMaxDim];
    double full[Quadric::size(kMaxDim)];
    std::fill_n(full, Quadric::size(q.dim), 0.0);
    if (triangle_basis(p[0], p[1], p[2], q.dim, basis)) Quadric::add_plane(full, p[0], basis, q.dim, q.dim, area);
    for (int v : tri) Quadric::add(q.quadric(std::size_t(v)), full, q.dim);
    // Border edges: a plane through the edge and the face normal, so that a
    // border slides along itself rather than inwards.
    for (int k = 0; k < 3; ++k) {
      const int u = tri[std::size_t(k)], w = tri[std::size_t((k + 1) % 3)];
      if (!g.border[std::size_t(u)] || !g.border[std::size_t(w)]) continue;
      int uses = 0;
      for (int t : g.incident[std::size_t(u)]) uses += other_count(g, t, u, w);
      if (uses != 1) continue;
      const Eigen::Vector3d pu(q.x[std::size_t(u)][0], q.x[std::size_t(u)][1], q.x[std::size_t(u)][2]);
      const Eigen::Vector3d pw(q.x[std::size_t(w)][0], q.x[std::size_t(w)][1], q.x[std::size_t(w)][2]);
      const Eigen::Vector3d edge = pw - pu;
      if (!(edge.norm() > 0)) continue;
      double cb[2][kMaxDim] = {};
      const Eigen::Vector3d e0 = edge.normalized(), e1 = normal.normalized();
      for (int i = 0; i < 3; ++i) cb[0][i] = e0[i], cb[1][i] = e1[i];
      double constraint[Quadric::size(kMaxDim)];
      std::fill_n(constraint, Quadric::size(q.dim), 0.0);
      Quadric::add_plane(constraint, q.x[std::size_t(u)].data(), cb, 3, q.dim, kBoundaryWeight * edge.squaredNorm());
      for (int v : {u, w}) Quadric::add(q.quadric(std::size_t(v)), constraint, q.dim);
    }
  }

}

// Where two vertices meet when their edge collapses, and what it costs there.
struct Meeting {
  float cost = 0;
  bool swap = false;  // `to` goes onto `from`, which stays where it is
  std::array<double, kMaxDim> x{};
};

// Phase 3a: the meeting point of `from` and `to`. At the minimum of their
// summed quadric (Garland and Heckbert, 1997), attributes included, where it
// lies within an edge length of the edge's middle; else at an end or the
// middle, whichever costs least. A locked vertex stays where it is, and so
// does a border vertex joined by one inside.
Meeting meeting(const GroupTopology& g, const GroupQuadrics& q, int from, int to, bool optimal) {
  const std::size_t f = std::size_t(from), t = std::size_t(to);
  Meeting m;
  const bool to_fixed = g.locked[t] || (g.border[t] && !g.border[f]);
  if (to_fixed || !optimal) {
    m.x = q.x[t];
    m.cost = float(std::max(0.0, Quadric::evaluate(q.quadric(f), m.x.data(), q.dim) +
                                     Quadric::evaluate(q.quadric(t), m.x.data(), q.dim)));
    return m;
  }
  const double* a = q.x[f].data();
  const double* b = q.x[t].data();
  double length2 = 0, off2 = 0, at = 0;
  for (int i = 0; i < 3; ++i) length2 += (a[i] - b[i]) * (a[i] - b[i]);
  if (sum_minimum(q.dim, q.quadric(f), q.quadric(t), m.x.data(), &at)) {
    for (int i = 0; i < 3; ++i) off2 += (m.x[std::size_t(i)] - 0.5 * (a[i] + b[i])) * (m.x[std::size_t(i)] - 0.5 * (a[i] + b[i]));
    if (off2 <= length2) {
      m.cost = float(std::max(0.0, at));
      return m;
    }
  }
  m.x = {};
  std::array<double, kMaxDim> middle{};
  for (int i = 0; i < q.dim; ++i) middle[std::size_t(i)] = 0.5 * (a[i] + b[i]);
  auto cost_at = [&](const double* x) {
    return Quadric::evaluate(q.quadric(f), x, q.dim) + Quadric::evaluate(q.quadric(t), x, q.dim);
  };
  const double at_to = cost_at(b), at_from = cost_at(a), at_middle = cost_at(middle.data());
  m.x = q.x[t];
  double best = at_to;
  if (at_middle < best) best = at_middle, m.x = middle;
  if (at_from < best && !g.border[t]) best = at_from, m.x = q.x[f], m.swap = true;
  m.cost = float(std::max(0.0, best));
  return m;
}

// Phase 3b: collapses the cheapest edge first until `target` triangles are
// left or none may collapse, telling `collapsed(from, to, x, live)`
// of each: `from` went onto `to`, now at x, leaving `live` triangles.
template <class Collapsed>
void collapse_to_target(std::size_t target, bool optimal, GroupTopology* group, GroupQuadrics* quadrics,
                        Collapsed collapsed) {
  GroupTopology& g = *group;
  GroupQuadrics& q = *quadrics;
  const std::size_t nv = q.x.size();
  // The heap holds each edge's cost and the versions of the quadrics it
  // came from; the meeting point is computed again for the few that are
  // tried (on the bunny 226 k of 2.95 M), as neither quadric changed since.
  // Keeping every meeting point (88 bytes each) made a group's working set
  // twice what a core's cache holds.
  std::vector<std::uint32_t> version(nv, 0);
  auto candidate = [&](int from, int to) {
    const Meeting m = meeting(g, q, from, to, optimal);
    return Candidate{m.cost, from, to, version[std::size_t(from)], version[std::size_t(to)]};
  };
  std::priority_queue<Candidate, std::vector<Candidate>, std::greater<Candidate>> heap;
  std::vector<std::uint8_t> removed(nv, 0);
  std::vector<int> around;
  // Both directions of an edge, or one where both ends move freely (they
  // meet at the same point either way).
  auto push_edge = [&](int v, int w) {
    const bool v_free = !g.locked[std::size_t(v)] && !g.border[std::size_t(v)];
    const bool w_free = !g.locked[std::size_t(w)] && !g.border[std::size_t(w)];
    if (!g.locked[std::size_t(v)]) heap.push(candidate(v, w));
    if (!g.locked[std::size_t(w)] && !(optimal && v_free && w_free)) heap.push(candidate(w, v));
  };
  auto push_around = [&](int v) {  // each edge at v, once
    around.clear();
    for (int t : g.incident[std::size_t(v)]) {
      if (g.dead[std::size_t(t)]) continue;
      for (int w : g.tris[std::size_t(t)])
        if (w != v && !g.mark[std::size_t(w)]) g.mark[std::size_t(w)] = 1, around.push_back(w);
    }
    for (int w : around) {
      g.mark[std::size_t(w)] = 0;
      push_edge(v, w);
    }
  };
  // Initially each edge once: from its smaller end.
  for (std::size_t v = 0; v < nv; ++v) {
    around.clear();
    for (int t : g.incident[v])
      for (int w : g.tris[std::size_t(t)])
        if (w > int(v) && !g.mark[std::size_t(w)]) g.mark[std::size_t(w)] = 1, around.push_back(w);
    for (int w : around) {
      g.mark[std::size_t(w)] = 0;
      push_edge(int(v), w);
    }
  }
  std::size_t live = g.tris.size();
  while (live > target && !heap.empty()) {
    Candidate c = heap.top();
    heap.pop();
    if (removed[std::size_t(c.from)] || removed[std::size_t(c.to)]) continue;
    // Stale: a collapse since moved an end, and pushed the edge afresh then
    // (push_around). Recomputing stale entries instead, and requeueing
    // them, computed a ninth of all meetings, each a duplicate.
    if (c.from_version != version[std::size_t(c.from)] || c.to_version != version[std::size_t(c.to)]) {
      continue;
    }
    const Meeting m = meeting(g, q, c.from, c.to, optimal);
    if (m.swap) std::swap(c.from, c.to);
    if (!collapse_allowed(&g, c.from, c.to, Eigen::Vector3d(m.x[0], m.x[1], m.x[2]), q.x, q.scale)) continue;
    // Apply: triangles on the edge die, the rest of from's move to `to`,
    // which moves to the meeting point.
    for (int t : g.incident[std::size_t(c.from)]) {
      if (g.dead[std::size_t(t)]) continue;
      if (other_count(g, t, c.from, c.to)) {
        g.dead[std::size_t(t)] = 1;
        --live;
        continue;
      }
      for (int& v : g.tris[std::size_t(t)])
        if (v == c.from) v = c.to;
      g.incident[std::size_t(c.to)].push_back(t);
    }
    removed[std::size_t(c.from)] = 1;
    q.x[std::size_t(c.to)] = m.x;
    collapsed(c.from, c.to, m.x.data(), live);
    Quadric::add(q.quadric(std::size_t(c.to)), q.quadric(std::size_t(c.from)), q.dim);
    ++version[std::size_t(c.to)];
    auto& list = g.incident[std::size_t(c.to)];
    list.erase(std::remove_if(list.begin(), list.end(), [&](int t) { return g.dead[std::size_t(t)] != 0; }),
               list.end());
    push_around(c.to);
  }
}

CollapseSequence simplify_steps(const std::vector<Triangle>& triangles, std::size_t floor,
                                const SimplifyInput& in) {
  const bool use_normals = in.normal_weight > 0 && !in.normals.empty();
  const bool use_colors = in.color_weight > 0 && !in.colors.empty();
  thread_local GroupTopology g;
  thread_local GroupQuadrics q;  // reused: a group's quadrics are about half a megabyte
  CollapseSequence s;
  s.global_ = load_group(triangles, in, &g);
  s.triangles_ = g.tris;
  group_quadrics(g, s.global_, in, use_normals, use_colors, &q);
  const int dim = q.dim;
  s.dim_ = dim;
  s.origin_.resize(q.x.size() * std::size_t(dim));
  for (std::size_t v = 0; v < q.x.size(); ++v) std::copy_n(q.x[v].data(), dim, &s.origin_[v * std::size_t(dim)]);
  collapse_to_target(floor, in.optimal_placement, &g, &q, [&](int from, int to, const double* x, std::size_t live) {
    s.from_.push_back(from);
    s.to_.push_back(to);
    s.at_.insert(s.at_.end(), x, x + dim);
    s.live_.push_back(std::uint32_t(live));
  });
  return s;
}

std::size_t CollapseSequence::step_keeping(std::size_t triangles) const {
  if (triangles_.size() < triangles) return 0;
  // live_ falls step by step: the first step below `triangles`.
  return std::size_t(std::partition_point(live_.begin(), live_.end(), [&](std::uint32_t left) { return left >= triangles; }) -
                     live_.begin());
}

// Phase 4: the group after its first `step` collapses, replayed from the
// start: each vertex's representative by the collapses' chains, triangles
// whose corners meet dropped (the link condition lets only the collapsed
// edges' triangles meet), and moved vertices numbered anew, -1, -2, ... in
// the order of their first use.
SimplifiedGroup CollapseSequence::take(std::size_t step, const SimplifyInput& in) const {
  const bool use_normals = in.normal_weight > 0 && !in.normals.empty();
  const bool use_colors = in.color_weight > 0 && !in.colors.empty();
  const std::size_t nv = global_.size(), dim = std::size_t(dim_);
  step = std::min(step, steps());
  thread_local std::vector<int> rep, first, incident;
  thread_local std::vector<double> x;
  thread_local std::vector<std::uint8_t> moved;
  rep.assign(nv, -1);
  moved.assign(nv, 0);
  x.assign(origin_.begin(), origin_.end());
  for (std::size_t i = 0; i < step; ++i) {
    const std::size_t to = std::size_t(to_[i]);
    rep[std::size_t(from_[i])] = to_[i];
    const double* at = &at_[i * dim];
    double* now = &x[to * dim];
    if (!std::equal(at, at + dim, now)) std::copy_n(at, dim, now), moved[to] = 1;
  }
  auto find = [&](int v) {
    int r = v;
    while (rep[std::size_t(r)] >= 0) r = rep[std::size_t(r)];
    while (rep[std::size_t(v)] >= 0 && rep[std::size_t(v)] != r) {
      const int next = rep[std::size_t(v)];
      rep[std::size_t(v)] = r;
      v = next;
    }
    return r;
  };

  SimplifiedGroup out;
  std::vector<std::array<int, 3>> live;
  live.reserve(triangles_at(step));
  out.kept.reserve(triangles_at(step));
  for (std::size_t i = 0; i < triangles_.size(); ++i) {
    const auto& t = triangles_[i];
    const std::array<int, 3> r{find(t[0]), find(t[1]), find(t[2])};
    if (r[0] != r[1] && r[1] != r[2] && r[0] != r[2]) live.push_back(r), out.kept.push_back(std::uint32_t(i));
  }
  std::vector<std::int32_t> id(global_.begin(), global_.end());
  out.triangles.reserve(live.size());
  for (const auto& t : live) {
    Triangle tri;
    for (int k = 0; k < 3; ++k) {
      const std::size_t v = std::size_t(t[std::size_t(k)]);
      if (moved[v] == 1) {
        moved[v] = 2;
        id[v] = -1 - std::int32_t(out.added_positions.size());
        const double* p = &x[v * dim];
        out.added_positions.push_back(Vec3f(float(p[0] / in.scale), float(p[1] / in.scale), float(p[2] / in.scale)));
        if (!in.normals.empty()) {
          Vec3f n = in.normals[std::size_t(global_[v])];
          if (use_normals) {
            const Vec3f solved{float(p[3]), float(p[4]), float(p[5])};
            if (solved.norm() > 0) n = solved.normalized();
          }
          out.added_normals.push_back(n);
        }
        if (!in.colors.empty()) {
          Rgb c = in.colors[std::size_t(global_[v])];
          if (use_colors) {
            for (int i = 0; i < 3; ++i)
              c[std::size_t(i)] = std::uint8_t(std::clamp(std::lround(p[dim - 3 + i] / in.color_weight * 255.0), 0L, 255L));
          }
          out.added_colors.push_back(c);
        }
      }
      tri[std::size_t(k)] = id[v];
    }
    out.triangles.push_back(tri);
  }

  // The error, measured: how far each vertex that went or moved lies, where
  // it was, from the triangles around the vertex that stands for it now: the
  // largest (a one-sided Hausdorff distance over the group's vertices) and
  // the mean.
  first.assign(nv + 1, 0);
  for (const auto& t : live)
    for (int v : t) ++first[std::size_t(v) + 1];
  for (std::size_t v = 0; v < nv; ++v) first[v + 1] += first[v];
  incident.resize(std::size_t(first[nv]));
  for (std::size_t t = 0; t < live.size(); ++t)
    for (int v : live[t]) incident[std::size_t(first[std::size_t(v)]++)] = int(t);
  for (std::size_t v = nv; v > 0; --v) first[v] = first[v - 1];
  first[0] = 0;
  auto point = [&](int v) { return Eigen::Vector3d(x[std::size_t(v) * dim], x[std::size_t(v) * dim + 1], x[std::size_t(v) * dim + 2]); };
  double worst = 0, sum = 0;
  std::size_t count = 0;
  for (std::size_t r = 0; r < nv; ++r) {
    if (rep[r] < 0 && !moved[r]) continue;
    const std::size_t stands = std::size_t(find(int(r)));
    const Eigen::Vector3d p(origin_[r * dim], origin_[r * dim + 1], origin_[r * dim + 2]);
    double nearest = std::numeric_limits<double>::infinity();
    for (int i = first[stands]; i < first[stands + 1]; ++i) {
      const auto& tri = live[std::size_t(incident[std::size_t(i)])];
      nearest = std::min(nearest, point_triangle_distance2(p, point(tri[0]), point(tri[1]), point(tri[2])));
    }
    if (!std::isfinite(nearest)) continue;
    nearest = std::sqrt(nearest);
    worst = std::max(worst, nearest), sum += nearest, ++count;
  }
  out.error = float(worst / in.scale);
  out.mean_error = count > 0 ? float(sum / double(count) / in.scale) : 0.0f;
  return out;
}

SimplifiedGroup simplify_group(const std::vector<Triangle>& triangles, std::size_t target,
                               const SimplifyInput& in) {
  const CollapseSequence s = simplify_steps(triangles, target, in);
  return s.take(s.steps(), in);
}

}  // namespace scan2lod
