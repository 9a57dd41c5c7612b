// Oriented points between Python and the library. load_points() returns
// (points, normals), views of one OrientedPoints that also holds what numpy
// does not show (each point's sample spacing, confidence and colour); given
// back unchanged to reconstruct() or build(), those views stand for the
// whole set again, without a copy, so that the reconstruction is the command
// line's.
#pragma once

#include <scan2lod/acquisition/point_cloud_files.h>
#include <scan2lod/core/types.h>

#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <vector>

namespace scan2lod::python {

inline constexpr const char* kPointsOwner = "scan2lod.OrientedPoints";

// What `points` and `normals` (None: to be estimated) hold: either `loaded`,
// oriented points ready for the library (load_points()'s own, or the
// arrays copied once), or `cloud`, positions whose normals
// cloud_to_oriented_points() must estimate (acquisition/cloud_normals.h)
// without the GIL.
struct PointsArgument {
  std::shared_ptr<const OrientedPoints> loaded;
  std::shared_ptr<PointCloud> cloud;
};
PointsArgument points_argument(const pybind11::handle& points, const pybind11::handle& normals);

// Each warning as a Python UserWarning. With the GIL held.
void warn_all(const std::vector<std::string>& warnings);

}  // namespace scan2lod::python
