// Stanford range-grid PLY files and the .conf files that place them
// (Lee 2007, §4.3.1). Reading and writing go through PCL's PLY reader/writer,
// which understands `element range_grid`; this layer adds validation and
// messages a user can act on.
#pragma once

#include <scan2lod/core/types.h>

#include <string>
#include <vector>

namespace scan2lod {

// Reads an ASCII or binary range-grid PLY (`obj_info num_cols/num_rows`,
// `element vertex`, `element range_grid`) into its scan frame.
// Throws InputError naming the file and element when the header or body is wrong.
RangeImage read_range_grid_ply(const std::string& path);

// Writes `image` as a binary little-endian range-grid PLY, through a temporary
// file renamed into place. Empty cells (NaN) get an empty index list.
void write_range_grid_ply(const std::string& path, const RangeImage& image);

// One `bmesh FILE tx ty tz qi qj qk qr` line of a Stanford .conf.
struct ConfEntry {
  std::string file;  // resolved against the .conf's folder
  ScanPose pose;     // scan frame -> common frame
};

// Parses a .conf. The quaternion is applied as its conjugate, p' = R(q)^T p + t,
// which is the convention the Stanford data was registered in (checked against
// bun_zipper.ply: 98 um mean, versus ~40 mm for R(q) p + t).
// Throws InputError for a malformed line, naming the line number.
std::vector<ConfEntry> read_conf(const std::string& path);

// Writes a .conf with one bmesh line per entry (file names written relative).
void write_conf(const std::string& path, const std::vector<ConfEntry>& entries);

}  // namespace scan2lod
