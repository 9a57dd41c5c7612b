// The local origin of a mesh read in double (io/mesh_file.h, read_mesh with an
// origin): georeferenced coordinates (10^5 to 10^7 m) lose centimetres to a
// metre as floats, so such a mesh is held as floats about a point near it,
// file frame = origin + position. A mesh that floats hold well is left where
// it is, so that reading it with an origin changes nothing.
#pragma once

#include <scan2lod/core/types.h>

#include <vector>

namespace scan2lod {

// Whether rounding every coordinate of `positions` to a float moves none by
// more than a millionth of their bounding box's diagonal (always, for
// coordinates that are floats already). Non-finite coordinates are ignored.
bool floats_hold(const std::vector<Vec3d>& positions);

// The most that rounding to floats moves a coordinate of a point in the box
// [low, high]: half a float step at its largest coordinate.
double float_rounding(const Vec3d& low, const Vec3d& high);

// Whether floats hold every point of the box [low, high] that well:
// float_rounding() is at most a millionth of its diagonal. What a format of
// floats (STL) needs to hold a file's frame.
bool floats_hold(const Vec3d& low, const Vec3d& high);

// Zero when floats_hold(positions), else the bounding box's centre rounded to
// a multiple of the largest power of two not above its diagonal (a short
// binary number, so that the positions about it are as short).
Vec3d local_origin(const std::vector<Vec3d>& positions);

// `positions` about `origin`, as floats: float(p - origin), the difference
// taken in double.
std::vector<Vec3f> positions_about(const std::vector<Vec3d>& positions, const Vec3d& origin);

}  // namespace scan2lod
