// Everything a user may point scan2lod at becomes one set of oriented points in a
// common frame: a Stanford .conf with its range-grid PLYs, single range-grid PLYs,
// organized PCDs, or meshes (.ply with faces, .obj, .off, .stl).
#pragma once

#include "acquisition/lattice_normals.h"
#include "core/types.h"

#include <string>
#include <vector>

namespace scan2lod {

struct AcquisitionOptions {
  LatticeNormalOptions lattice;
  int threads = 0;  // 0: all cores
};

struct AcquisitionReport {
  std::size_t range_images = 0;
  std::size_t meshes = 0;
  std::vector<std::string> files;  // every file read, in order
};

// @param[in] inputs  paths; the kind is told by extension and, for .ply, by header
// @return the merged oriented points (normals outward, in the common frame)
// Throws InputError naming the file for unreadable input, and when the inputs
// hold no usable points at all.
OrientedPoints load_oriented_points(const std::vector<std::string>& inputs,
                                    const AcquisitionOptions& options = {},
                                    AcquisitionReport* report = nullptr);

}  // namespace scan2lod
