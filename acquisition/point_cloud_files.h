// Unorganized point clouds: the files users have when there is no range image
// behind the points, or the scans were merged and exported by other software.
// Vertex-only PLY (ASCII or binary, optionally with normals and colours) and
// .xyz / .pts text are read here; unorganized PCDs in organized_pcd.h. Normals
// are estimated where the file has none (cloud_normals.h).
#pragma once

#include <scan2lod/core/types.h>

#include <optional>
#include <string>
#include <vector>

namespace scan2lod {

// Points as the file holds them, in the file's frame.
struct PointCloud {
  std::vector<Vec3f> positions;
  std::vector<Vec3f> normals;  // empty, or one per point (as written: not yet checked)
  std::vector<Rgb> colors;     // empty, or one per point
  std::optional<Vec3f> viewpoint;  // the sensor's position, when the file gives one
  // The direction toward a sensor too far away to have a position (airborne
  // LiDAR: +Z); normals are oriented to face it where there is no viewpoint.
  std::optional<Vec3f> sensor_direction;
  // The point of the file's own frame that positions are relative to: file
  // frame = origin + position. Zero but for georeferenced files (LAS), whose
  // coordinates a float cannot hold within the file's scale.
  Vec3d origin = Vec3d::Zero();
  std::string source;              // file it came from, for messages
  std::vector<std::string> warnings;  // what the reader skipped, for the user
  std::size_t size() const { return positions.size(); }
};

// Reads the vertices of a PLY without faces: `element vertex` with float or
// double x, y, z, optional nx, ny, nz (or normal_x, ...), optional uchar red,
// green, blue; other scalar properties are skipped. Elements before `vertex`
// must be empty; anything after the vertices is ignored.
// Throws InputError naming the file and the header line or vertex that is wrong.
PointCloud read_point_cloud_ply(const std::string& path);

// Reads .xyz / .pts text, one point a line, blank-separated numbers:
//   3 values: x y z          4: x y z intensity        7: x y z intensity r g b
//   6 values: x y z nx ny nz when the first point's last three are a unit vector
//             (within 1%), else x y z r g b (0 to 255)
//   9 values: x y z nx ny nz r g b
// A first line holding one integer (the .pts point count) is skipped, as are
// blank lines and lines starting with '#' or '//'. Every line must have the
// first data line's number of values. Throws InputError naming the line.
PointCloud read_point_cloud_text(const std::string& path);

// Writes `cloud` as a binary little-endian PLY of vertices (x y z, nx ny nz when
// it has normals, red green blue when it has colours), atomically.
void write_point_cloud_ply(const std::string& path, const PointCloud& cloud);

}  // namespace scan2lod
