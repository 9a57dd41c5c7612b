// Triangle meshes on disk: the pipeline's input models and its outputs. PLY,
// OFF and STL are read, and PLY, OFF and STL written, by OpenMesh (but for
// positions in double, below, which it keeps only as floats); .vtp goes
// through VTK; glTF is written (io/gltf_file.h) and read (io/gltf_read.h) by
// tinygltf; OBJ is read by a small parser here (Debian's OpenMesh asserts,
// i.e. aborts, on some broken OBJ faces) and written by io/obj_writer.h
// (OpenMesh's drops vertex colours). The OpenMesh adapters copy straight
// between files and the plain TriangleMesh, never through a half-edge mesh, so
// non-manifold faces (marching-cubes and LOD output can have them) are
// neither dropped nor split.
//
// Georeferenced meshes (LAS surveys: coordinates of 10^5 to 10^7 m, where a
// float's step is 1 cm to 1 m) are held as float positions about a local
// origin, file frame = origin + position, added in double. Writers given that
// origin put the mesh back in the file's frame; read_mesh() with an origin
// takes such a file back to a local frame without rounding it to floats.
#pragma once

#include <scan2lod/core/types.h>

#include <cstddef>
#include <string>

namespace scan2lod {

// Reads a mesh from a .ply, .obj, .off, .stl, .vtp, .glb or .gltf file
// (extension decides, case-insensitive; glTF as io/gltf_read.h describes: the
// default scene with node transforms applied, quantized or not). Polygons are
// fan-triangulated. Vertex normals and colours are kept when the file has
// them (else `normals`/`colors` are empty; OBJ colours are the `v x y z r g b`
// extension, OBJ normals count only when every used vertex has one). STL has
// no shared vertices: OpenMesh merges equal corner positions and skips
// triangles that collapse by it.
// Throws InputError naming the file when it is missing, has an unknown
// extension, cannot be parsed, is truncated, has no vertices or no faces, or
// has a face that names a vertex that does not exist. A Stanford range-grid
// PLY (`element range_grid`) is rejected with a hint to read it as a scan.
// Caveat: a damaged *compressed* .vtp (as ParaView writes by default) can crash
// inside VTK's reader; damaged uncompressed ones (as written here) are reported.
// The XML's counts are checked against the file's size before VTK allocates,
// but VTK sizes a cell array's connectivity by the last value of its offsets
// data, so a few hundred bytes can still make it ask for gigabytes.
// Thread-safe; PLY/OFF/STL reads are serialised internally (OpenMesh's readers
// are singletons with per-file state).
TriangleMesh read_mesh(const std::string& path);

// The same, about a local origin: file frame = *origin + position, the sum in
// double. Coordinates are taken in double where the file holds more than a
// float (PLY `double` x/y/z, OBJ and ASCII OFF text, VTP Float64 points, glTF
// node transforms), and *origin is
//   zero           when rounding every coordinate to a float moves none by
//                  more than a millionth of the bounding box's diagonal (any
//                  file of floats: positions are then read_mesh(path)'s, bit
//                  for bit), else
//   a local point  the box's centre, rounded to a multiple of the largest
//                  power of two not above the diagonal.
// Throws as read_mesh(path) does.
TriangleMesh read_mesh(const std::string& path, Vec3d* origin);

// Writes `mesh` to `path` in the format its extension names:
//   .ply  binary little-endian, with vertex normals and colours when present
//   .obj  ASCII, with `vn` normals and `v x y z r g b` colours when present
//         (9 significant digits)
//   .off  ASCII (NOFF/COFF when normals/colours are present; colours as four
//         integers, RGBA with alpha 255; both three and four are read)
//   .stl  binary (normals and colours are not stored)
//   .vtp  VTK XML poly data, raw appended binary (uncompressed), with
//         "Normals" and an unsigned-char "RGB" array when present
//   .glb  glTF 2.0 binary, .gltf glTF 2.0 JSON with the buffer embedded:
//         normals and colours when present; quantized unless options say not
// With a non-zero `options.origin` the mesh is written in the file frame,
// origin + position, each sum taken in double:
//   .ply  positions as `property double x/y/z` (written here; OpenMesh 9.0
//         writes float positions only), the rest as above
//   .obj  positions with the 17 significant digits that round-trip a double
//   .off  the same, written here
//   .vtp  Float64 points
//   .glb  float positions as above under a node translation of `origin`
//         (composed with the quantization's translation), as glTF intends
//   .stl  float only: the sums rounded to floats; refused (InputError,
//         naming the formats that keep the frame) when half a float step at
//         the largest coordinate exceeds a millionth of the bounding box's
//         diagonal (at UTM northings a step is 0.5 m)
// With a zero origin every format writes exactly what it wrote before.
// Only the vertices some triangle uses are written, in their order in `mesh`
// (io/used_vertices.h); returns how many that is.
// `mesh` must be consistent: every triangle index < positions.size(), and
// normals/colors empty or one per vertex. Output goes through write_atomically,
// so a failure or a signal leaves nothing behind.
// Throws InputError for an unknown extension (listing the supported ones), an
// inconsistent or empty mesh, or a write failure (e.g. a missing directory).
struct MeshWriteOptions {
  bool quantize = true;   // glTF: KHR_mesh_quantization
  std::string generator;  // glTF: asset.generator
  // The point of the file's frame that the mesh's positions are relative to
  // (e.g. AcquisitionReport::origin, LodModel::origin): zero, or a finite point.
  Vec3d origin = Vec3d::Zero();
};
std::size_t write_mesh(const std::string& path, const TriangleMesh& mesh, const MeshWriteOptions& options = {});

// Throws InputError unless write_mesh could write `path`: a known extension in
// an existing folder, and not a folder itself. Commands call it before long
// work, not after.
void check_mesh_output(const std::string& path);

// The same for a mesh within `bounds` (local positions) written about
// `origin`: also throws where write_mesh would refuse it in the file's frame
// (STL where floats do not hold it). Commands call it once they know the
// origin and roughly where the mesh will lie (the input points, the model).
void check_mesh_output(const std::string& path, const Vec3d& origin, const Aabb& bounds);

}  // namespace scan2lod
