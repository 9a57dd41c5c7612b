#include <scan2lod/bench/model_build.h>

#include <scan2lod/pipeline/build_model.h>

namespace scan2lod::bench {

TimedModel build_model_timed(const OrientedPoints& points, int resolution, bool clusters) {
  BuildOptions options;
  options.reconstruct.resolution = resolution;
  options.clusters = clusters;
  options.strategy = BuildStrategy::kInCore;
  BuildReport report;
  TimedModel t;
  t.model = build_model(points, nullptr, options, &report);
  t.full_triangles = report.full_triangles;
  t.reconstruct_seconds = report.seconds_reconstruct;
  t.octree_seconds = report.seconds_octree - report.seconds_numbering;
  t.numbering_seconds = report.seconds_numbering;
  t.cluster_seconds = report.seconds_clusters;
  return t;
}

}  // namespace scan2lod::bench
