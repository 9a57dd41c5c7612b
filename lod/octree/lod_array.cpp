#include <scan2lod/lod/octree/lod_array.h>

#include <scan2lod/lod/level_budget.h>
#include <scan2lod/lod/octree/extract.h>

#include <algorithm>
#include <cmath>

namespace scan2lod {
namespace {

// Triangles after each of the expansions [begin, end) of lod.order, into
// accumulated[begin + 1 ..= end]; accumulated[begin] too when begin is 0.
// It follows the extracted meshes exactly: an expansion replaces the node's
// triangles by its children's and re-triangulates the cut nodes across a face
// or an edge, whose transitions change (a finer node across a corner alone
// splits nothing, lod/octree/transition.h); those are recounted in one batch. Hole
// patches show once all the nodes around their rims have expanded.
void accumulate(const McOctree& tree, const LodArray& lod, std::size_t begin, std::size_t end,
                std::int64_t* accumulated) {
  const std::size_t n = tree.size();
  std::vector<std::uint8_t> flags(n, 0);  // extract.h's marks: bit 0 expanded
  std::vector<std::int32_t> current(n, 0);  // triangles each cut node emits now
  mark_cut(tree, lod, begin, flags.data());
  std::int64_t triangles = 0;
  // The cut at `begin`, counted in batches.
  std::vector<std::int32_t> cut;
  for (std::size_t node = 0; node < n; ++node)
    if (flags[node] && !(flags[node] & 1)) cut.push_back(std::int32_t(node));
  std::vector<std::int32_t> counts(cut.size());
  node_triangle_counts(tree, cut.data(), int(cut.size()), flags, counts.data());
  for (std::size_t i = 0; i < cut.size(); ++i) triangles += current[cut[i]] = counts[i];
  std::vector<std::int32_t> patch_waiting(tree.patch_groups(), 0);
  std::vector<std::vector<std::int32_t>> patches_of(n);
  for (std::size_t g = 0; g < tree.patch_groups(); ++g) {
    for (std::int32_t k = tree.patches.needs_first[g]; k < tree.patches.needs_first[g + 1]; ++k)
      if (!(flags[tree.patches.needs[k]] & 1)) {
        ++patch_waiting[g];
        patches_of[tree.patches.needs[k]].push_back(std::int32_t(g));
      }
    if (patch_waiting[g] == 0) triangles += tree.patches.group_first[g + 1] - tree.patches.group_first[g];
  }
  if (begin == 0) accumulated[0] = triangles;
  std::int32_t recount[8 + 18], batch[8 + 18];
  for (std::size_t i = begin; i < end; ++i) {
    const std::int32_t node = lod.order[i];
    flags[node] = 1;
    triangles -= current[node];
    int size = 0;
    for (int c = 0; c < tree.nodes.child_counts[node]; ++c) recount[size++] = tree.nodes.first_child[node] + c;
    if (std::size_t(node) < tree.internal_nodes())
      for (const int c : splitting_cells())
        if (const std::int32_t q = tree.transitions.neighbours[node][std::size_t(c)];
            q >= 0 && !(flags[q] & 1) && (flags[tree.nodes.parents[q]] & 1))
          recount[size++] = q;
    node_triangle_counts(tree, recount, size, flags, batch);
    for (int k = 0; k < size; ++k) {
      triangles += batch[k] - current[recount[k]];
      current[recount[k]] = batch[k];
    }
    for (std::int32_t g : patches_of[node])
      if (--patch_waiting[g] == 0) triangles += tree.patches.group_first[g + 1] - tree.patches.group_first[g];
    accumulated[i + 1] = triangles;
  }
}

}  // namespace

// Counted in two halves at once: the second half starts from the cut at its
// first expansion, counted whole.
std::vector<std::int64_t> accumulation_table(const McOctree& tree, const LodArray& lod) {
  const std::size_t full = lod.order.size(), half = full / 2;
  std::vector<std::int64_t> accumulated(full + 1, 0);
  if (full < 4096) {
    accumulate(tree, lod, 0, full, accumulated.data());
    return accumulated;
  }
#pragma omp parallel sections num_threads(2)
  {
#pragma omp section
    accumulate(tree, lod, 0, half, accumulated.data());
#pragma omp section
    accumulate(tree, lod, half, full, accumulated.data());
  }
  return accumulated;
}


std::vector<std::size_t> monotone_priorities(const LodArray& lod) {
  // Records of the running maximum, ending at full detail.
  std::vector<std::size_t> levels;
  std::int64_t best = -1;
  auto inside = lod.inside_steps.begin();
  for (std::size_t i = std::min(lod.pinned, lod.full()); i < lod.accumulated.size(); ++i) {
    while (inside != lod.inside_steps.end() && std::size_t(*inside) < i) ++inside;
    if (inside != lod.inside_steps.end() && std::size_t(*inside) == i) continue;
    if (lod.accumulated[i] >= best) best = lod.accumulated[i], levels.push_back(i);
  }
  const std::int64_t full = lod.accumulated.back();
  while (!levels.empty() && lod.accumulated[levels.back()] > full) levels.pop_back();
  if (levels.empty() || levels.back() != lod.full()) levels.push_back(lod.full());
  const bool root_inside = !lod.inside_steps.empty() && lod.inside_steps.front() == 0;
  if (!root_inside && levels.front() != 0 && lod.accumulated[0] <= lod.accumulated[levels.front()])
    levels.insert(levels.begin(), 0);
  return levels;
}

namespace {
// The largest offered level at or below `priority`.
std::size_t snap(const std::vector<std::size_t>& levels, std::size_t priority) {
  auto it = std::upper_bound(levels.begin(), levels.end(), priority);
  return it == levels.begin() ? levels.front() : *(it - 1);
}
}  // namespace

std::size_t priority_for_percent(const LodArray& lod, double percent) {
  percent = std::clamp(percent, 0.0, 100.0);
  const std::size_t priority = std::size_t(std::llround(percent / 100.0 * double(lod.full())));
  if (percent > 0.0 && priority <= lod.pinned) return std::min(lod.pinned, lod.full());
  return snap(monotone_priorities(lod), priority);
}

std::size_t priority_for_triangles(const LodArray& lod, std::int64_t triangles) {
  // Offered levels grow in triangles: the last one that fits.
  const std::vector<std::size_t> levels = monotone_priorities(lod);
  std::size_t best = levels.front();
  for (std::size_t level : levels)
    if (lod.accumulated[level] <= triangles) best = level;
  if (lod.accumulated[best] <= triangles || lod.pinned == 0) return best;
  best = 0;
  // Below the smallest offered level: the largest that fits inside the pinned
  // prefix, where the count still never decreases from one record to the next.
  std::int64_t record = -1;
  for (std::size_t i = 1; i < lod.pinned && lod.accumulated[i] <= triangles; ++i)
    if (lod.accumulated[i] >= record && lod.accumulated[i] >= lod.accumulated[best]) record = lod.accumulated[i], best = i;
  return best;
}

std::size_t priority_for_budget(const LodArray& lod, std::int64_t triangles) {
  const std::size_t under = priority_for_triangles(lod, triangles);
  const std::int64_t under_count = lod.accumulated[under] <= triangles ? lod.accumulated[under] : -1;
  std::size_t over = under;
  std::int64_t over_count = -1;
  for (const std::size_t level : monotone_priorities(lod))
    if (lod.accumulated[level] > triangles) {
      over = level, over_count = lod.accumulated[level];
      break;
    }
  return take_level_over(under_count, over_count, triangles) ? over : under;
}

}  // namespace scan2lod
