// Plain values passed between the pipeline's stages. Library types (PCL clouds,
// OpenMesh meshes, VTK poly data) stay at the edges; these are what stages share.
#pragma once

#include <scan2lod/core/array_view.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace scan2lod {

using Vec3f = Eigen::Vector3f;
using Vec3d = Eigen::Vector3d;
using Rgb = std::array<std::uint8_t, 3>;
using Triangle = std::array<std::int32_t, 3>;

// The key of the undirected edge between vertices a and b (either order):
// meshes are joined and counted edge by edge in flat hash maps and sorted lists.
inline std::uint64_t edge_key(std::int32_t a, std::int32_t b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

// One range image in its own scan frame: a cols x rows lattice of samples, NaN where
// the scanner had no return. The scanner sits on the +z side of the frame.
struct RangeImage {
  int cols = 0;
  int rows = 0;
  std::vector<Vec3f> points;      // cols*rows, row-major; NaN x for "no return"
  std::vector<Rgb> colors;        // empty, or cols*rows
  std::vector<float> confidence;  // empty, or cols*rows
  std::string source;             // file it came from, for messages
  // The scanner's position in the scan frame for a perspective sensor (a PCD's
  // VIEWPOINT); none for a scanner that looks down -z from the +z side
  // (Stanford range grids, virtual scans).
  std::optional<Vec3f> viewpoint;
  std::vector<std::string> warnings;  // what the reader skipped, for the user
};

// Rigid placement of a scan in the common frame: p_world = rotation * p_scan + translation.
struct ScanPose {
  Eigen::Matrix3f rotation = Eigen::Matrix3f::Identity();
  Vec3f translation = Vec3f::Zero();
};

// Oriented samples of a surface. Normals are unit length and point outward.
struct OrientedPoints {
  std::vector<Vec3f> positions;
  std::vector<Vec3f> normals;
  std::vector<Rgb> colors;        // empty, or one per point
  std::vector<float> confidence;  // empty, or one per point
  std::vector<float> spacing;     // empty, or the local sample spacing at each point

  std::size_t size() const { return positions.size(); }
  bool has_colors() const { return !colors.empty(); }
  // Appends other; attributes present on one side only are dropped (or filled).
  void append(const OrientedPoints& other);
};

// Indexed triangle mesh with optional per-vertex attributes. Triangles are
// counter-clockwise seen from outside.
struct TriangleMesh {
  std::vector<Vec3f> positions;
  std::vector<Vec3f> normals;  // empty, or one per vertex
  std::vector<Rgb> colors;     // empty, or one per vertex
  std::vector<Triangle> triangles;
};

struct Aabb {
  Vec3f min = Vec3f::Constant(std::numeric_limits<float>::max());
  Vec3f max = Vec3f::Constant(-std::numeric_limits<float>::max());
  void extend(const Vec3f& p) { min = min.cwiseMin(p); max = max.cwiseMax(p); }
  bool empty() const { return !(min.array() <= max.array()).all(); }
  Vec3f extent() const { return max - min; }
  float diagonal() const { return empty() ? 0.f : extent().norm(); }
};

Aabb bounds(ArrayView<Vec3f> points);

// Whether a, b and c lie in line: the triangle's height is under a millionth
// of its longest side (points that coincide count too). Hole filling avoids
// such triangles, and crack patching the node faces that hold three such
// crossings.
bool in_line(const Vec3f& a, const Vec3f& b, const Vec3f& c);

}  // namespace scan2lod
