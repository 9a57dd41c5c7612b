// The LOD model exactly as `scan2lod build` makes it (cli/build_command.cpp),
// each stage timed on its own, for the benchmarks: the LOD report's build
// table and the reconstruction report's scaling over R.
#pragma once

#include "core/types.h"
#include "lod/lod_model.h"
#include "reconstruct/marching_cubes.h"

namespace scan2lod::bench {

struct TimedModel {
  Reconstruction reconstruction;
  LodModel model;
  double reconstruct_seconds = 0;  // reconstruct()
  double octree_seconds = 0;       // build_mc_octree(reconstruction), its distance field included
  double numbering_seconds = 0;    // number_nodes() and model_from_octree()
  double cluster_seconds = 0;      // add_cluster_hierarchy(); 0 without the clusters
  // The octree's build: octree + numbering.
  double octree_model_seconds() const { return octree_seconds + numbering_seconds; }
  // The model build: everything after the reconstruction.
  double model_seconds() const { return octree_seconds + numbering_seconds + cluster_seconds; }
};

// reconstruct(points) at `resolution` with default options otherwise, then
// build_mc_octree(reconstruction) with default OctreeOptions, number_nodes()
// and model_from_octree(), then, with `clusters`, add_cluster_hierarchy over
// the reconstruction's mesh (sharing the octree's vertices) with default
// ClusterOptions (all cores): `scan2lod build` without flags (both
// structures). Benchmarks of the octree alone pass clusters = false.
TimedModel build_model_timed(const OrientedPoints& points, int resolution, bool clusters = true);

}  // namespace scan2lod::bench
