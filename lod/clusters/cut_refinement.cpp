#include <scan2lod/lod/clusters/cut_refinement.h>

#include <scan2lod/lod/clusters/cluster_hierarchy.h>
#include <scan2lod/lod/clusters/group_simplify.h>
#include <scan2lod/lod/clusters/paged_model.h>
#include <scan2lod/lod/clusters/position_weld.h>
#include <scan2lod/lod/level_budget.h>

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace scan2lod {

float rank_to_refine(const ClusterCutTable& table, std::int64_t budget) {
  const std::int64_t most = std::int64_t(double(budget) * kRefineHeadroom);
  // triangles never rise along the table: the first entry within `most`.
  const auto it = std::partition_point(table.triangles.begin(), table.triangles.end(),
                                       [&](std::int64_t t) { return t > most; });
  const std::size_t i = std::size_t(it - table.triangles.begin());
  std::size_t from = 0;
  if (it != table.triangles.end() && *it > budget) {
    from = i;
  } else {
    // None within the headroom: where the cut under the budget also falls
    // more than kBudgetTolerance short (a gap at the coarse end), the
    // coarsest above.
    const bool short_under = it == table.triangles.end() || double(*it) < (1.0 - kBudgetTolerance) * double(budget);
    if (!short_under || i == 0) return -1;
    from = i - 1;
  }
  return table.triangles[from] <= kRefineMostTriangles ? table.ranks[from] : -1.f;
}

CutRefiner::Result CutRefiner::refine(const Vertices& vertices, std::vector<Triangle>* triangles,
                                      std::size_t target, std::vector<std::uint32_t>* kept) {
  Result result;
  kept->clear();
  if (triangles->size() <= target) return result;
  // Phase 1: the cut's vertices welded by position, over the cut alone.
  used_.clear();
  for (const Triangle& t : *triangles) used_.insert(used_.end(), t.begin(), t.end());
  std::sort(used_.begin(), used_.end());
  used_.erase(std::unique(used_.begin(), used_.end()), used_.end());
  points_.resize(used_.size());
  for (std::size_t i = 0; i < used_.size(); ++i) points_[i] = vertices.positions[std::size_t(used_[i])];
  weld_ = weld_positions(points_, 1);
  auto rep = [&](std::int32_t v) {
    const std::size_t i = std::size_t(std::lower_bound(used_.begin(), used_.end(), v) - used_.begin());
    return used_[std::size_t(weld_[i])];
  };
  welded_.clear();
  whole_.clear();
  for (std::size_t t = 0; t < triangles->size(); ++t) {
    const Triangle& o = (*triangles)[t];
    const Triangle w{rep(o[0]), rep(o[1]), rep(o[2])};
    if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]) continue;
    welded_.push_back(w);
    whole_.push_back(std::uint32_t(t));
  }

  // Phase 2: half-edge collapses, with the build's quadric weights.
  const ClusterOptions options;
  SimplifyInput in;
  in.positions = vertices.positions;
  in.normals = vertices.normals;
  in.colors = vertices.colors;
  const float diagonal = bounds(points_).diagonal();
  in.scale = diagonal > 0 ? 1.f / diagonal : 1.f;
  in.normal_weight = options.normal_weight;
  in.color_weight = options.color_weight;
  in.optimal_placement = false;
  const SimplifiedGroup g = simplify_group(welded_, target, in);
  if (g.triangles.size() >= welded_.size()) return result;
  if (!g.added_positions.empty()) throw std::logic_error("CutRefiner: a half-edge collapse placed a vertex");

  // Phase 3: each corner a collapse left where it was keeps the cut's own
  // vertex there, so that seams of normals or colours stay.
  std::vector<Triangle> out(g.triangles.size());
  kept->resize(g.triangles.size());
  for (std::size_t i = 0; i < g.triangles.size(); ++i) {
    const std::uint32_t whole = whole_[g.kept[i]];
    const Triangle& was = (*triangles)[whole];
    const Triangle& w = welded_[g.kept[i]];
    for (int k = 0; k < 3; ++k) out[i][std::size_t(k)] = g.triangles[i][std::size_t(k)] == w[std::size_t(k)] ? was[std::size_t(k)] : g.triangles[i][std::size_t(k)];
    (*kept)[i] = whole;
  }
  *triangles = std::move(out);
  result.refined = true;
  result.error = g.error;
  return result;
}

CutRefiner::Result CutRefiner::refine_pages(const ClusterPages& pages, std::vector<Triangle>* triangles,
                                            std::size_t target, std::vector<std::uint32_t>* kept) {
  const TriangleMesh read = pages.compact(*triangles);
  std::vector<std::int32_t> model_id(read.positions.size());
  for (std::size_t t = 0; t < triangles->size(); ++t)
    for (std::size_t k = 0; k < 3; ++k) model_id[std::size_t(read.triangles[t][k])] = (*triangles)[t][k];
  std::vector<std::int32_t> order(model_id.size()), place(model_id.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](std::int32_t a, std::int32_t b) { return model_id[std::size_t(a)] < model_id[std::size_t(b)]; });
  TriangleMesh mesh;
  for (std::size_t i = 0; i < order.size(); ++i) {
    const std::size_t v = std::size_t(order[i]);
    place[v] = std::int32_t(i);
    mesh.positions.push_back(read.positions[v]);
    if (!read.normals.empty()) mesh.normals.push_back(read.normals[v]);
    if (!read.colors.empty()) mesh.colors.push_back(read.colors[v]);
  }
  mesh.triangles = read.triangles;
  for (Triangle& t : mesh.triangles)
    for (std::int32_t& v : t) v = place[std::size_t(v)];
  const Result r = refine({mesh.positions, mesh.normals, mesh.colors}, &mesh.triangles, target, kept);
  if (!r.refined) return r;
  triangles->resize(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (std::size_t k = 0; k < 3; ++k)
      (*triangles)[t][k] = model_id[std::size_t(order[std::size_t(mesh.triangles[t][k])])];
  return r;
}

}  // namespace scan2lod
