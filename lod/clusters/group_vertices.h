// A group's vertices numbered in the order of their first use, by a hash
// the size of the group. Per-thread tables of every mesh vertex did this
// before: 4 bytes a vertex a thread (100 MB at 10^8 points), filled anew on
// every thread a round started and every time the mesh gained vertices, so
// that each group paid for the whole mesh: most of the cluster stage's page
// faults, and a cost that grew with the mesh, not the group.
#pragma once

#include <scan2lod/core/flat_hash.h>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace scan2lod {

class GroupVertices {
 public:
  // Forgets the last group, keeping the room unless it is far more than the
  // group needed: a table sized for one of the first pass's meshlet runs (up
  // to 2^20 triangles), emptied whole for every small group after it, was up
  // to 7 % of a build's instructions on the bunny at R = 256, depending on
  // which thread had cut the large runs.
  void clear() {
    if (index_.capacity() > 16 * std::max<std::size_t>(global_.size(), 1024))
      index_ = FlatHashMap(global_.size());
    else if (!global_.empty())
      index_.clear();
    global_.clear();
  }
  // The group index of mesh vertex `v` (negative ids too: a group's placed
  // vertices), numbering it next if it is new.
  int local(std::int32_t v) {
    const int next = int(global_.size());
    const int i = index_.insert(std::uint64_t(std::uint32_t(v)), next);
    if (i == next) global_.push_back(v);
    return i;
  }
  // Group index -> mesh vertex.
  const std::vector<std::int32_t>& global() const { return global_; }
  std::size_t size() const { return global_.size(); }

 private:
  FlatHashMap index_;
  std::vector<std::int32_t> global_;
};

}  // namespace scan2lod
