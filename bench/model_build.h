// The LOD model exactly as `scan2lod build` makes it (cli/build_command.cpp),
// each stage timed on its own, for both benchmarks: the LOD report's build
// table and the reconstruction report's scaling over R.
#pragma once

#include "core/types.h"
#include "lod/model_file.h"
#include "reconstruct/marching_cubes.h"

namespace scan2lod::bench {

struct TimedModel {
  Reconstruction reconstruction;
  LodModel model;
  double reconstruct_seconds = 0;  // reconstruct()
  double octree_seconds = 0;       // build_mc_octree(reconstruction), its distance field included
  double numbering_seconds = 0;    // number_nodes()
  // The model build: everything after the reconstruction.
  double model_seconds() const { return octree_seconds + numbering_seconds; }
};

// reconstruct(points) at `resolution` with default options otherwise, then
// build_mc_octree(reconstruction) with default OctreeOptions and
// number_nodes(), as `scan2lod build` without flags.
TimedModel build_model_timed(const OrientedPoints& points, int resolution);

}  // namespace scan2lod::bench
