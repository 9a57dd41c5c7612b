#include <scan2lod/lod/clusters/cluster_partition.h>

#include <scan2lod/core/error.h>

#include <metis.h>

#include <algorithm>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <utility>

namespace scan2lod {
namespace {

constexpr idx_t kDirectParts = 64;     // more parts than this go through regions
constexpr idx_t kPartsPerRegion = 32;

// METIS 5.1 seeds and draws from the C library's one random state (srand,
// rand), so two partitions at once on two threads interleave their draws and
// the model would differ from run to run. One at a time, each call sees the
// sequence its seed starts.
std::mutex metis_mutex;

// METIS k-way partition of `graph` into `parts` (> 1) parts.
std::vector<idx_t> metis_parts(const WeightedGraph& graph, idx_t parts) {
  idx_t nodes = idx_t(graph.size()), constraints = 1, cut = 0;
  std::vector<idx_t> xadj(graph.first.begin(), graph.first.end());
  std::vector<idx_t> adjncy(graph.adjacency.begin(), graph.adjacency.end());
  std::vector<idx_t> adjwgt(graph.weights.begin(), graph.weights.end());
  std::vector<idx_t> part(graph.size(), 0);
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED] = 1;  // the same model from the same mesh
  options[METIS_OPTION_NUMBERING] = 0;
  const std::lock_guard<std::mutex> one_at_a_time(metis_mutex);
  // Bisection is METIS's own advice below 8 parts; k-way is faster above.
  const int status = parts < 8 ? METIS_PartGraphRecursive(&nodes, &constraints, xadj.data(), adjncy.data(), nullptr,
                                                          nullptr, adjwgt.data(), &parts, nullptr, nullptr, options,
                                                          &cut, part.data())
                               : METIS_PartGraphKway(&nodes, &constraints, xadj.data(), adjncy.data(), nullptr,
                                                     nullptr, adjwgt.data(), &parts, nullptr, nullptr, options, &cut,
                                                     part.data());
  if (status != METIS_OK) throw std::runtime_error("METIS failed to partition a graph of " +
                                                   std::to_string(graph.size()) + " nodes (status " +
                                                   std::to_string(status) + ")");
  return part;
}

// The subgraph of the nodes in `members` (global node ids), renumbered.
WeightedGraph subgraph(const WeightedGraph& graph, const std::vector<std::int32_t>& members,
                       std::vector<std::int32_t>* local) {
  WeightedGraph sub;
  for (std::size_t i = 0; i < members.size(); ++i) (*local)[std::size_t(members[i])] = std::int32_t(i);
  for (std::int32_t m : members) {
    for (std::int32_t k = graph.first[std::size_t(m)]; k < graph.first[std::size_t(m) + 1]; ++k) {
      const std::int32_t l = (*local)[std::size_t(graph.adjacency[std::size_t(k)])];
      if (l < 0) continue;
      sub.adjacency.push_back(l);
      sub.weights.push_back(graph.weights[std::size_t(k)]);
    }
    sub.first.push_back(std::int32_t(sub.adjacency.size()));
  }
  for (std::int32_t m : members) (*local)[std::size_t(m)] = -1;
  return sub;
}

}  // namespace

std::vector<std::int32_t> partition_graph(const WeightedGraph& graph, int part_size, int* parts) {
  const std::size_t n = graph.size();
  std::vector<std::int32_t> part(n, 0);
  // METIS balances to within 3 %: aim below the cap, then halve what still exceeds it.
  const std::size_t target = std::max<std::size_t>(1, std::size_t(part_size * 0.94));
  const idx_t first_parts = idx_t((n + target - 1) / target);
  std::vector<std::int32_t> local(n, -1);
  std::vector<std::vector<std::int32_t>> members;
  if (first_parts > kDirectParts) {
    // Split into regions first, then each region into parts. Written when
    // triangles went through here (thousands of parts at once cost METIS
    // seconds); now cluster graphs of over 64 groups do, and every figure in
    // bench/lod was measured with this path in place.
    const idx_t regions = (first_parts + kPartsPerRegion - 1) / kPartsPerRegion;
    const std::vector<idx_t> r = metis_parts(graph, regions);
    std::vector<std::vector<std::int32_t>> region(static_cast<std::size_t>(regions));
    for (std::size_t i = 0; i < n; ++i) region[std::size_t(r[i])].push_back(std::int32_t(i));
    for (const std::vector<std::int32_t>& m : region) {
      const idx_t k = idx_t((m.size() + target - 1) / target);
      if (k <= 1) {
        members.push_back(m);
        continue;
      }
      const std::vector<idx_t> p = metis_parts(subgraph(graph, m, &local), k);
      const std::size_t base = members.size();
      members.resize(base + std::size_t(k));
      for (std::size_t i = 0; i < m.size(); ++i) members[base + std::size_t(p[i])].push_back(m[i]);
    }
  } else {
    if (first_parts > 1 && n > 1) {
      const std::vector<idx_t> p = metis_parts(graph, first_parts);
      for (std::size_t i = 0; i < n; ++i) part[i] = std::int32_t(p[i]);
    }
    members.resize(std::size_t(std::max<idx_t>(first_parts, 1)));
    for (std::size_t i = 0; i < n; ++i) members[std::size_t(part[i])].push_back(std::int32_t(i));
  }
  // Oversized parts bisected until they fit.
  for (std::size_t p = 0; p < members.size(); ++p) {
    while (members[p].size() > std::size_t(part_size)) {
      const WeightedGraph sub = subgraph(graph, members[p], &local);
      const std::vector<idx_t> halves = metis_parts(sub, 2);
      std::vector<std::int32_t> keep, moved;
      for (std::size_t i = 0; i < members[p].size(); ++i) (halves[i] ? moved : keep).push_back(members[p][i]);
      if (keep.empty() || moved.empty()) {  // METIS could not split it: cut it in node order
        keep.assign(members[p].begin(), members[p].begin() + std::ptrdiff_t(members[p].size() / 2));
        moved.assign(members[p].begin() + std::ptrdiff_t(members[p].size() / 2), members[p].end());
      }
      members[p] = std::move(keep);
      members.push_back(std::move(moved));
    }
  }

  // Renumber in the order of each part's first node, dropping empty ones.
  std::vector<std::int32_t> owner(members.size(), -1);
  for (std::size_t p = 0; p < members.size(); ++p)
    for (std::int32_t i : members[p]) part[std::size_t(i)] = std::int32_t(p);
  std::int32_t next = 0;
  for (std::size_t i = 0; i < n; ++i) {
    std::int32_t& o = owner[std::size_t(part[i])];
    if (o < 0) o = next++;
    part[i] = o;
  }
  *parts = next;
  return part;
}

}  // namespace scan2lod
