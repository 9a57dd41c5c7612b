// Every uniform cut of a cluster hierarchy, for tests that check them all.
#pragma once

#include <scan2lod/lod/clusters/cluster_cut.h>
#include <scan2lod/lod/lod_model.h>

#include <algorithm>
#include <vector>

namespace scan2lod::testing {

// Each stored uniform cut once: those a triangle count gets (one per rank
// where the count changes) and those an error gets (one per distinct group
// error).
inline std::vector<LevelRequest> every_uniform_cut(const ClusterHierarchy& h) {
  std::vector<LevelRequest> out;
  for (std::int64_t t : cluster_cut_table(h).triangles) {
    out.push_back(LevelRequest::at_most_triangles(t));
    out.back().refine = false;  // the stored cut itself
  }
  std::vector<float> errors{0.f};
  for (const GroupBound& g : h.groups) errors.push_back(g.error);
  std::sort(errors.begin(), errors.end());
  errors.erase(std::unique(errors.begin(), errors.end()), errors.end());
  for (float e : errors) out.push_back(LevelRequest::at_error(e));
  return out;
}

}  // namespace scan2lod::testing
