#include <scan2lod/lod/clusters/cluster_cut.h>

#include <scan2lod/lod/clusters/paged_model.h>
#include <scan2lod/lod/level_budget.h>

#include <algorithm>
#include <stdexcept>
#include <cmath>
#include <limits>

namespace scan2lod {

namespace {

// The clusters with own(c) <= t < parent(c) for `value(g)` of each group.
template <class Value>
void select_clusters(const ClusterHierarchy& h, float t, Value value, std::vector<std::int32_t>* selected) {
  selected->clear();
  const std::size_t n = h.clusters.size();
  for (std::size_t c = 0; c < n; ++c) {
    const Cluster& cl = h.clusters[c];
    const bool own_applied = cl.own_group < 0 || value(cl.own_group) <= t;
    const bool parent_applied = cl.parent_group >= 0 && value(cl.parent_group) <= t;
    if (own_applied && !parent_applied) selected->push_back(std::int32_t(c));
  }
}

// Each group's rank (the errors where a model has none).
const float* ranks(const ClusterHierarchy& h, std::vector<float>* scratch) {
  if (h.group_ranks.size() == h.groups.size()) return h.group_ranks.data();
  scratch->resize(h.groups.size());
  for (std::size_t g = 0; g < h.groups.size(); ++g) (*scratch)[g] = h.groups[g].error;
  return scratch->data();
}

}  // namespace

void select_clusters_by_error(const ClusterHierarchy& h, float error, std::vector<std::int32_t>* selected) {
  const GroupBound* groups = h.groups.data();
  select_clusters(h, error, [groups](std::int32_t g) { return groups[g].error; }, selected);
}

void select_clusters_by_rank(const ClusterHierarchy& h, float rank, std::vector<std::int32_t>* selected) {
  std::vector<float> scratch;
  const float* r = ranks(h, &scratch);
  select_clusters(h, rank, [r](std::int32_t g) { return r[g]; }, selected);
}

float cut_error(const ClusterHierarchy& h, const std::vector<std::int32_t>& selected) {
  float error = 0;
  for (std::int32_t c : selected) {
    const std::int32_t g = h.clusters[std::size_t(c)].own_group;
    if (g >= 0) error = std::max(error, h.groups[std::size_t(g)].error);
  }
  return error;
}

void select_clusters_for_view(const ClusterHierarchy& h, const CameraView& camera, float pixel_error,
                              std::vector<float>* projected, std::vector<std::int32_t>* selected) {
  const float half_fov = 0.5f * camera.fov_degrees * float(M_PI) / 180.f;
  const float pixels_per_unit_at_unit_distance = float(camera.height) / (2.f * std::tan(half_fov));
  const std::size_t groups = h.groups.size();
  projected->resize(groups);
  float* p = projected->data();
  const float ex = camera.eye.x(), ey = camera.eye.y(), ez = camera.eye.z();
  for (std::size_t g = 0; g < groups; ++g) {
    const GroupBound& b = h.groups[g];
    const float dx = b.center[0] - ex, dy = b.center[1] - ey, dz = b.center[2] - ez;
    const float distance = std::sqrt(dx * dx + dy * dy + dz * dz) - b.radius;
    p[g] = distance > 0 ? b.error * pixels_per_unit_at_unit_distance / distance
                        : std::numeric_limits<float>::infinity();
  }
  selected->clear();
  const std::size_t n = h.clusters.size();
  for (std::size_t c = 0; c < n; ++c) {
    const Cluster& cl = h.clusters[c];
    const bool own_applied = cl.own_group < 0 || p[cl.own_group] <= pixel_error;
    const bool parent_applied = cl.parent_group >= 0 && p[cl.parent_group] <= pixel_error;
    if (own_applied && !parent_applied) selected->push_back(std::int32_t(c));
  }
}

ClusterCutTable cluster_cut_table(const ClusterHierarchy& h) {
  // Applying a group swaps the clusters it consumed for the ones it made.
  std::vector<std::int64_t> change(h.groups.size(), 0);
  for (const Cluster& c : h.clusters) {
    if (c.own_group >= 0) change[std::size_t(c.own_group)] += c.triangle_count;
    if (c.parent_group >= 0) change[std::size_t(c.parent_group)] -= c.triangle_count;
  }
  std::vector<float> scratch;
  const float* rank = ranks(h, &scratch);
  std::vector<std::int32_t> order(h.groups.size());
  for (std::size_t g = 0; g < order.size(); ++g) order[g] = std::int32_t(g);
  std::sort(order.begin(), order.end(),
            [&](std::int32_t a, std::int32_t b) { return rank[std::size_t(a)] < rank[std::size_t(b)]; });
  ClusterCutTable table;
  table.ranks.push_back(0);
  table.triangles.push_back(h.full_triangles);
  std::int64_t count = h.full_triangles;
  for (std::size_t i = 0; i < order.size(); ++i) {
    count += change[std::size_t(order[i])];
    const float r = rank[std::size_t(order[i])];
    if (i + 1 < order.size() && rank[std::size_t(order[i + 1])] == r) continue;
    table.ranks.push_back(r);
    table.triangles.push_back(count);
  }
  return table;
}

float rank_for_triangles(const ClusterCutTable& table, std::int64_t budget) {
  // triangles never rise along the table: the first entry within budget.
  const auto it = std::partition_point(table.triangles.begin(), table.triangles.end(),
                                       [&](std::int64_t t) { return t > budget; });
  if (it == table.triangles.end()) return table.ranks.back();
  return table.ranks[std::size_t(it - table.triangles.begin())];
}

float rank_for_budget(const ClusterCutTable& table, std::int64_t budget) {
  const auto it = std::partition_point(table.triangles.begin(), table.triangles.end(),
                                       [&](std::int64_t t) { return t > budget; });
  const std::size_t i = std::size_t(it - table.triangles.begin());
  const std::int64_t under = i < table.triangles.size() ? table.triangles[i] : -1;
  const std::int64_t over = i > 0 ? table.triangles[i - 1] : -1;  // the fewest triangles above the budget
  if (take_level_over(under, over, budget)) return table.ranks[i - 1];
  return i < table.triangles.size() ? table.ranks[i] : table.ranks.back();
}

void emit_clusters(const ClusterHierarchy& h, const std::vector<std::int32_t>& selected,
                   std::vector<Triangle>* triangles) {
  if (h.spool)
    throw std::logic_error("emit_clusters: the hierarchy's triangles are spooled on disk; save the model, or "
                           "load_spooled(), first");
  if (h.paged) return h.paged->emit(h, selected, triangles);
  std::size_t total = triangles->size();
  for (std::int32_t c : selected) total += h.clusters[std::size_t(c)].triangle_count;
  triangles->reserve(total);
  // Ranges appended as they are: no zero-filling first, no work per triangle.
  for (std::int32_t c : selected) {
    const Cluster& cl = h.clusters[std::size_t(c)];
    if (cl.triangle_count == 0) continue;  // no range to copy (and no pointer to copy from)
    const Triangle* first = h.triangles.data() + cl.first_triangle;
    triangles->insert(triangles->end(), first, first + cl.triangle_count);
  }
}

}  // namespace scan2lod
