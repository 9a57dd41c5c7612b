// A mesh as range data (Lee 2007, §4.3.1, §6.3): "We took the vertex of the
// mesh as the point and the average of this vertex's adjacent triangles'
// normal as the normal of this point."
#pragma once

#include <scan2lod/core/types.h>

namespace scan2lod {

// Turns a mesh's vertices into oriented points.
// @param[in] mesh  triangles counter-clockwise seen from outside (the
//                  TriangleMesh contract); indices must be < positions.size()
// @return one point per vertex that some triangle uses, in vertex order, with
//   - normal: the area-weighted average of the adjacent triangles' normals
//     (the sum of their unnormalised cross products), normalised. Area
//     weighting keeps slivers from tilting the normal. Vertices whose sum
//     vanishes (only degenerate triangles, or opposite sheets cancelling)
//     are dropped, as are vertices no triangle uses.
//   - spacing: the mean length of the edges incident to the vertex (each
//     adjacent triangle contributes its two edges at the vertex), i.e. the
//     local sample spacing that tells reconstruction how far from the data a
//     signed distance can be trusted.
//   - colors: the vertex colours when the mesh has them, else empty.
// The mesh's own vertex normals, if any, are ignored: the seed derives
// normals from the triangles, which also fixes their orientation.
OrientedPoints mesh_to_oriented_points(const TriangleMesh& mesh);

}  // namespace scan2lod
