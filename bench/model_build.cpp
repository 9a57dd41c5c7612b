#include "bench/model_build.h"

#include "bench/bench_support.h"
#include "lod/lod_array.h"
#include "lod/octree_order.h"
#include "lod/mc_octree.h"

#include <utility>

namespace scan2lod::bench {

TimedModel build_model_timed(const OrientedPoints& points, int resolution, bool clusters) {
  TimedModel t;
  ReconstructOptions options;
  options.resolution = resolution;
  auto start = Clock::now();
  t.reconstruction = reconstruct(points, options);
  t.reconstruct_seconds = seconds_since(start);
  start = Clock::now();
  McOctree tree = build_mc_octree(t.reconstruction);
  t.octree_seconds = seconds_since(start);
  start = Clock::now();
  LodArray lod = number_nodes(tree);
  t.model = model_from_octree(std::move(tree), std::move(lod));
  t.numbering_seconds = seconds_since(start);
  if (clusters) {
    start = Clock::now();
    ClusterOptions cluster_options;
    cluster_options.threads = options.threads;
    add_cluster_hierarchy(&t.model, t.reconstruction.mesh, /*shares_vertices=*/true, cluster_options);
    t.cluster_seconds = seconds_since(start);
  }
  return t;
}

}  // namespace scan2lod::bench
