// A scan set: range images with the poses that place them in a common frame,
// as a Stanford .conf describes them. Used to convert whole sets between
// formats and to write virtual scans.
#pragma once

#include <scan2lod/core/types.h>

#include <string>
#include <vector>

namespace scan2lod {

struct PlacedScan {
  RangeImage image;  // lattice in the scan frame
  ScanPose pose;     // scan frame -> common frame
};

// Reads range images: a .conf (each bmesh line with its pose), range-grid
// .ply files and organized .pcd files (identity pose, or the PCD's VIEWPOINT).
// Files are read in parallel. Throws InputError naming the file on bad input.
std::vector<PlacedScan> read_scan_set(const std::vector<std::string>& inputs, int threads = 0);

// Writes DIR/<name>.ply for each scan as binary little-endian range-grid PLYs and
// DIR/<conf_name> placing them, creating DIR if needed. Names come from each
// image's source file (made unique), or scan_000, scan_001, ... Every file is
// written atomically. Throws InputError when DIR or a file cannot be written.
void write_scan_set(const std::string& dir, const std::vector<PlacedScan>& scans,
                    const std::string& conf_name = "scans.conf");

}  // namespace scan2lod
