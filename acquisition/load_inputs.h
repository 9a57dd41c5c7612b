// Everything a user may point scan2lod at becomes one set of oriented points in a
// common frame: a Stanford .conf with its range-grid PLYs, single range-grid PLYs,
// organized PCDs, point clouds (vertex-only .ply, unorganized .pcd, .xyz/.pts
// text, LAS), or meshes (.ply with faces, .obj, .off, .stl).
#pragma once

#include <scan2lod/acquisition/cloud_normals.h>
#include <scan2lod/acquisition/lattice_normals.h>
#include <scan2lod/core/types.h>

#include <functional>
#include <string>
#include <vector>

namespace scan2lod {

struct AcquisitionOptions {
  LatticeNormalOptions lattice;
  CloudNormalOptions cloud;
  int threads = 0;  // 0: all cores
  // Range-grid PLYs carry no pose: several given without their .conf are
  // refused unless the caller says they already share one frame.
  bool unregistered = false;
};

struct AcquisitionReport {
  std::size_t range_images = 0;
  std::size_t meshes = 0;
  std::size_t clouds = 0;             // point clouds
  std::size_t clouds_estimated = 0;   // of those, the ones whose normals were estimated
  std::vector<std::string> files;  // every file read, in order
  std::vector<std::string> warnings;  // what the readers skipped, file by file
  // The point of the inputs' own frame that the loaded points are relative
  // to: input frame = origin + point, added in double. Zero unless an input
  // is LAS: georeferenced coordinates (10^5 to 10^7 m) do not fit a float
  // within the file's scale, so every input is shifted by the first LAS
  // input's origin (acquisition/las_file.h, las_local_origin()). Outputs
  // that should lie in the inputs' frame add it back.
  Vec3d origin = Vec3d::Zero();
};

// @param[in] inputs  paths; the kind is told by extension and, for .ply, by header
// @return the merged oriented points (normals outward, in the common frame)
// Throws InputError naming the file for unreadable input, and when the inputs
// hold no usable points at all; and, unless options.unregistered, for two or
// more range-grid PLYs given without the .conf that places them (or beside a
// .conf), naming the .conf in their folder that lists them when there is one.
OrientedPoints load_oriented_points(const std::vector<std::string>& inputs,
                                    const AcquisitionOptions& options = {},
                                    AcquisitionReport* report = nullptr);

// One of `parts` contiguous runs of the input files (after a .conf is
// expanded into its scans), balanced by file size: the files one process of
// a job reads. Part 0 of 1 is every file.
struct InputShare {
  int part = 0;
  int parts = 1;
};

// The same, file by file: each file's oriented points go to `take` in input
// order, and no more files are in memory at once than there are cores. For
// inputs larger than memory (spooled to disk as they come). The report and
// the errors are those of load_oriented_points(), for the files of `share`
// (the common origin is every file's).
// `take` also gets the share of the files' bytes read so far (its part's
// file included), so that a caller can project what the rest will hold.
void stream_oriented_points(const std::vector<std::string>& inputs, const AcquisitionOptions& options,
                            AcquisitionReport* report,
                            const std::function<void(OrientedPoints&&, double read_share)>& take,
                            InputShare share = {});

// The parts as one set, in order (OrientedPoints::append); empties `parts`.
OrientedPoints merge_parts(std::vector<OrientedPoints>* parts);

}  // namespace scan2lod
