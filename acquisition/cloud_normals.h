// Point clouds -> oriented points: the file's normals where it has them, else
// normals estimated from the neighbours and oriented either toward the sensor
// (when the file names one) or consistently over a neighbour graph (Hoppe et
// al., "Surface reconstruction from unorganized points", 1992), then turned
// outward as a whole, or, for a sensor far away in a known direction (LAS:
// airborne, +Z), toward it.
#pragma once

#include <scan2lod/acquisition/point_cloud_files.h>
#include <scan2lod/core/types.h>

namespace scan2lod {

struct CloudNormalOptions {
  int neighbours = 20;        // points in each normal's local plane fit (Open3D EstimateNormals)
  int orient_neighbours = 12; // k of the graph that orientation propagates over
  int spacing_neighbours = 4; // spacing = mean distance to this many nearest points
  int threads = 0;            // 0: all cores
};

// @param[in] cloud  points in the common frame; normals (if any) need not be unit
// @return one oriented point per finite point with a usable normal, with
//   - normals: the cloud's own, normalised, when it has them (points whose normal
//     is zero or not finite are dropped); else estimated as described above;
//   - spacing: the mean distance to the spacing_neighbours nearest other points,
//     the local sample spacing that reconstruction scales its limits by;
//   - colours when the cloud has them; no confidence.
// Throws InputError naming the cloud's source when fewer than 3 points are usable.
OrientedPoints cloud_to_oriented_points(const PointCloud& cloud, const CloudNormalOptions& options = {});

}  // namespace scan2lod
