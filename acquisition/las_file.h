// Airborne and terrestrial LiDAR as ASPRS LAS 1.0 to 1.4 (ASPRS, "LAS
// Specification 1.4 - R15", 2019; the earlier versions' header blocks are
// prefixes of 1.4's). Debian has no LAS library (no PDAL, libLAS or LASzip),
// so the format is read here: the public header block and the point data
// records of any format 0 to 10 with any record length (bytes past a format's
// own are its "extra bytes"). VLRs and EVLRs are checked to fit and skipped.
// LAZ (LASzip-compressed LAS) is refused with how to convert it.
//
// LAS coordinates are georeferenced, X * scale + offset in a map projection's
// metres: UTM northings reach 10^7 m, where a float's step is 1 m. They are
// computed in double and shifted to a local origin before they become floats;
// the cloud carries that origin (PointCloud::origin), so that outputs can be
// shifted back into the file's frame.
#pragma once

#include <scan2lod/acquisition/point_cloud_files.h>
#include <scan2lod/core/types.h>

#include <cstdint>
#include <optional>
#include <string>

namespace scan2lod {

// What a LAS file's public header block says, checked against the file.
struct LasHeader {
  int version_minor = 0;               // LAS 1.minor, 0 to 4
  int point_format = 0;                // point data record format, 0 to 10
  std::size_t record_length = 0;       // bytes per point record, >= the format's own
  std::uint64_t points = 0;            // 1.4's 64-bit count where it has one, else the legacy count
  std::uint64_t point_data_offset = 0; // byte of the first point record
  Vec3d scale = Vec3d::Ones();
  Vec3d offset = Vec3d::Zero();
  Vec3d min = Vec3d::Zero(), max = Vec3d::Zero();  // the header's bounds, in the file's frame
  std::optional<Vec3d> first_point;                // the first record's coordinates, when there is one
};

// Reads the header block, and checks that the VLRs, the point records and
// the EVLRs fit in the file, without reading the points.
// Throws InputError naming the file, the field and what was expected for: no
// 'LASF' signature, a header block shorter than its version's (227 bytes for
// 1.0 to 1.2, 235 for 1.3, 375 for 1.4), a version other than 1.0 to 1.4,
// LAZ (a compressed point format), a point format above 10, a record length
// below the format's, a zero or non-finite scale, VLRs running into the
// points, more points than the file holds, and EVLRs that overlap the points
// or run past the end.
LasHeader read_las_header(const std::string& path);

// Where a file's points are shifted to: the centre of the header's bounds,
// or the first point where those bounds do not hold it (writers that leave
// them zero), moved onto the file's own grid (offset + k * scale) so that the
// shift is a coordinate the file itself can state.
Vec3d las_local_origin(const LasHeader& header);

// Reads every point record of the LAS file at `path` into a cloud whose
// positions are float(X * scale + offset - origin), the sum taken in double;
// cloud.origin = origin, so file frame = origin + position.
// Colours for the formats that have them (2, 3, 5, 7, 8, 10): LAS stores
// 16-bit RGB; the high byte is kept, unless no value exceeds 255, in which
// case the file holds 8-bit colours (a common departure from the spec) and
// they are kept as they are. No normals: LAS has none, and no sensor
// position either, so sensor_direction is +Z (airborne: one sensor far above).
// A warning (cloud.warnings) says when the header's bounds do not hold the
// points. Throws InputError as read_las_header does, and for a file that
// changes or ends while it is read.
PointCloud read_las(const std::string& path, const Vec3d& origin);

// The same at las_local_origin() of the file's own header.
PointCloud read_las(const std::string& path);

// The message for a LAZ file: LASzip is not in Debian, and how to convert.
std::string laz_refusal(const std::string& path);

}  // namespace scan2lod
