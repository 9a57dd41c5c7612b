// The LOD model exactly as `scan2lod build` makes it (build_model(), the one
// face the command line uses too), each stage timed on its own, for the
// benchmarks: the LOD report's build table and the reconstruction report's
// scaling over R.
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/lod/lod_model.h>

namespace scan2lod::bench {

struct TimedModel {
  LodModel model;
  std::size_t full_triangles = 0;  // the reconstruction's
  double reconstruct_seconds = 0;  // reconstruct()
  double octree_seconds = 0;       // build_mc_octree(reconstruction), its distance field included
  double numbering_seconds = 0;    // number_nodes() and model_from_octree()
  double cluster_seconds = 0;      // add_cluster_hierarchy(); 0 without the clusters
  // The octree's build: octree + numbering.
  double octree_model_seconds() const { return octree_seconds + numbering_seconds; }
  // The model build: everything after the reconstruction.
  double model_seconds() const { return octree_seconds + numbering_seconds + cluster_seconds; }
};

// build_model(points) at `resolution`, in core, with default options
// otherwise: `scan2lod build` without flags (both structures). Benchmarks of
// the octree alone pass clusters = false.
TimedModel build_model_timed(const OrientedPoints& points, int resolution, bool clusters = true);

}  // namespace scan2lod::bench
