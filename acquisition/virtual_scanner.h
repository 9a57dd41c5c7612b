// Range images generated from a mesh (Lee 2007, §4.4, §6.3: "The input data
// are generated from mesh models instead of range scanner"). Each view is an
// orthographic range camera, like a Cyberware scanner sweeping parallel rays:
// the scan frame has the scanner on its +z side looking along -z, x to the
// right and y up, the same convention as the Stanford range grids, so virtual
// scans and real ones go through the same reconstruction.
#pragma once

#include <scan2lod/acquisition/scan_set.h>
#include <scan2lod/core/types.h>

#include <string>
#include <vector>

namespace scan2lod {

struct VirtualScanOptions {
  int views = 14;    // directions spread evenly on the sphere (golden spiral)
  int width = 256;   // lattice columns per view
  int height = 256;  // lattice rows per view
};

using VirtualScan = PlacedScan;  // pose: scan frame -> mesh frame

// Scans `mesh` (triangle indices < positions.size()) from options.views
// directions around its bounding sphere
// (centre: the bounding box's centre; radius: the farthest vertex).
// View i looks at the centre from direction d_i of a golden-spiral (Fibonacci)
// set; its square-pixel window of width x height samples covers the bounding
// sphere's disc with a 2% margin, so nothing of the mesh is cut off.
// @return one VirtualScan per view, in order. In each image:
//   - points: width*height, row-major, row 0 = top (largest y), column 0 =
//     left (smallest x); the first surface hit along the ray, in the scan
//     frame, or NaN (all three coordinates) where the ray missed.
//   - colors: barycentric interpolation of the vertex colours at the hit when
//     the mesh has colours, else empty (missed samples: black).
//   - confidence: |cos| of the angle between the ray and the hit triangle's
//     normal (1 facing the scanner, ->0 at grazing angles), 0 where missed.
//   - the scan frame's origin is the bounding sphere's centre; pose maps it to
//     the mesh frame: p_mesh = pose.rotation * p_scan + pose.translation.
// Rays are cast by z-buffer rasterisation at the pixel centres, which for
// parallel rays is exact and needs no acceleration structure. (Debian 12's
// Open3D 0.16 RaycastingScene::CastRays reports no hit for any ray, even on a
// box, while its distance queries work; hence no Open3D here.) Both windings are
// hit, as a scanner sees the inside of an open surface; triangles without
// area, or seen edge-on, are never hit. Views are scanned in parallel (OpenMP).
// Throws InputError when the mesh has no non-degenerate triangle, and
// std::invalid_argument when views, width or height is < 1.
std::vector<VirtualScan> virtual_scan(const TriangleMesh& mesh, const VirtualScanOptions& options);

// The oriented points of every view of virtual_scan(mesh, options), as
// range_image_to_points makes them of real scans, in one cloud.
OrientedPoints virtual_scan_points(const TriangleMesh& mesh, const VirtualScanOptions& options);

// Virtual scans are written with write_scan_set (acquisition/scan_set.h):
// DIR/scan_000.ply, ... and DIR/scans.conf.

}  // namespace scan2lod
