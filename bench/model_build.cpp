#include "bench/model_build.h"

#include "bench/bench_support.h"
#include "lod/lod_array.h"
#include "lod/mc_octree.h"

namespace scan2lod::bench {

TimedModel build_model_timed(const OrientedPoints& points, int resolution) {
  TimedModel t;
  ReconstructOptions options;
  options.resolution = resolution;
  auto start = Clock::now();
  t.reconstruction = reconstruct(points, options);
  t.reconstruct_seconds = seconds_since(start);
  start = Clock::now();
  t.model.tree = build_mc_octree(t.reconstruction);
  t.octree_seconds = seconds_since(start);
  start = Clock::now();
  t.model.lod = number_nodes(t.model.tree);
  t.numbering_seconds = seconds_since(start);
  return t;
}

}  // namespace scan2lod::bench
