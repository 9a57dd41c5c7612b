// Range image -> oriented points (Lee 2007, §4.2, Fig. 4.2). Each sample's normal
// is the average of the normals of the up to four triangles it forms with its
// 4-neighbours in the lattice, turned toward the scanner (+z in the scan frame).
#pragma once

#include <scan2lod/core/types.h>

namespace scan2lod {

struct LatticeNormalOptions {
  // A lattice edge longer than this many times the sample's shortest lattice
  // edge spans a depth discontinuity (or a grazing view); its triangles are skipped.
  float max_edge_ratio = 4.0f;
};

// @param[in] image  cols x rows samples in the scan frame, NaN for no return
// @param[in] pose   scan frame -> common frame
// @return one oriented point per sample that has at least one valid lattice
//         triangle (isolated samples carry no normal and are dropped), in the
//         common frame; spacing = mean accepted lattice edge length; colours and
//         confidence carried when the image has them.
OrientedPoints range_image_to_points(const RangeImage& image, const ScanPose& pose,
                                     const LatticeNormalOptions& options = {});

}  // namespace scan2lod
