// Distance from a point to a triangle: Ericson, *Real-Time Collision
// Detection* (2005), 5.1.5, the closest point by Voronoi region. What the
// measures and the cluster hierarchy's group errors are made of.
#pragma once

#include <scan2lod/core/types.h>

namespace scan2lod {

// Squared distance from p to the triangle abc (a point or segment when abc is
// degenerate).
double point_triangle_distance2(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c);

}  // namespace scan2lod
