// Oriented points -> indexed triangle mesh by ratio-based marching cubes over a
// sparse grid (Lee 2007, §4.2-4.3). Each vertex sits on its cube edge at the ratio
// of the two corners' |signed distance|, not at the midpoint.
//
// Only cubes near data are touched: cubes that hold points (grown by `margin`),
// then, following the surface, any neighbour across a face that the surface
// crosses. Time and memory follow the surface area, not R^3. Afterwards small
// detached pieces are removed and small holes closed cube by cube; holes that
// marching cubes cannot close get rim triangles (CubeNodes::patch_triangles).
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/reconstruct/cube_grid.h>
#include <scan2lod/reconstruct/signed_distance.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace scan2lod {

struct ReconstructOptions {
  int resolution = 256;  // cubes per side of the bounding cube; a power of two
  int margin = 0;        // cubes grown around point-holding cubes before surface following
  // A cube reached by following the surface out of the point-holding cubes is
  // used only if its centre lies within this many max(cube size, local sample
  // spacing) of a point: small gaps in coverage close from both sides, while the
  // surface stops soon past the rim of a real hole.
  float reach = 2.5f;
  // Pieces of the surface with fewer than this fraction of its triangles are
  // removed (specks and fins off thin edges); 0 keeps every piece.
  double min_piece = 0.01;
  // Holes whose rim has at most max_hole * resolution edges are closed by
  // marching on into the cubes across them, with corners evaluated beyond the
  // distance limits; larger holes are the data's own and stay. 0 closes none.
  double max_hole = 0.4;
  int hole_rounds = 4;  // rings of cubes a hole is closed by from each side, at most
  SignedDistanceOptions distance;
  int threads = 0;       // 0: all cores
  // Memory the reconstruction may take, in bytes; 0: the machine's
  // (resolution_guard.h). A resolution whose estimate exceeds it is refused
  // before the grid is built.
  double memory_limit = 0;
};

// The leaf cube nodes (Lee 2007, §4.3.2, §5.1): every cube that emits triangles, with
// what the octree needs to build its parents. Flat arrays, one entry per cube;
// corner data is shared between cubes through corner indices.
struct CubeNodes {
  CubeGrid grid;
  std::vector<std::uint64_t> cube_keys;                     // packed (x, y, z) of the lower corner
  std::vector<std::uint8_t> cases;                          // mask of inside corners
  std::vector<std::uint16_t> triangle_masks;                // kept triangles of the case (bit t)
  std::vector<std::array<std::int32_t, 8>> corners;         // into the corner arrays below
  std::vector<std::array<std::int32_t, 12>> edge_vertices;  // mesh vertex on each edge, or -1
  std::vector<std::array<float, 12>> edge_ratios;           // crossing along edge from its lower corner, 0 if none

  std::vector<std::uint64_t> corner_keys;  // packed grid coordinates
  std::vector<float> corner_distances;     // signed distance (never NaN for emitting cubes)
  std::vector<Rgb> corner_colors;          // empty without colour input

  // Triangles that close small holes over existing vertices (hole_filling.h),
  // appended to the mesh after the cubes' triangles.
  std::vector<Triangle> patch_triangles;

  std::size_t size() const { return cube_keys.size(); }
};

struct ReconstructStats {
  std::size_t points = 0;
  std::size_t cubes_touched = 0;      // cubes whose corners were evaluated
  std::size_t corners_evaluated = 0;
  std::size_t cubes_emitting = 0;
  std::size_t following_rounds = 0;   // surface-following passes after the seed cubes
  std::size_t triangles_dropped = 0;  // triangles of pieces under min_piece
  std::size_t cubes_hole_closing = 0; // cubes added to close small holes
  std::size_t patch_triangles = 0;    // triangles over the rims of holes cubes could not close
  // Wall-clock seconds per stage.
  double seconds_index = 0, seconds_distances = 0, seconds_emit = 0, seconds_cleanup = 0,
         seconds_attributes = 0;
};

struct Reconstruction {
  TriangleMesh mesh;  // vertices with normals (and colours if the points had them)
  CubeNodes leaves;
  ReconstructStats stats;
  std::vector<std::string> warnings;  // advice for the user, e.g. a grid far finer than the data
};

// @param[in] points  oriented points, normals outward; positions must be finite
// Throws InputError for no points, non-finite points, a bad resolution, or one
// whose estimated memory exceeds options.memory_limit (check_resolution_fits).
Reconstruction reconstruct(const OrientedPoints& points, const ReconstructOptions& options = {});

// What a caller says of a reconstruction with no triangle at `resolution`:
// its points and the cubes near them, and to try a coarser one, named as the
// caller's user gives it (`resolution_flag`: "--resolution", "resolution").
std::string no_surface_message(const Reconstruction& r, int resolution, const std::string& resolution_flag);

// Area-weighted vertex normals of a mesh (unit length; zero for unused vertices).
std::vector<Vec3f> vertex_normals(const TriangleMesh& mesh);

}  // namespace scan2lod
