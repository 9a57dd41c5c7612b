// Triangle meshes on disk: the pipeline's input models and its outputs. PLY,
// OFF and STL are read, and PLY, OFF and STL written, by OpenMesh; .vtp goes
// through VTK; glTF is written (io/gltf_file.h) and read (io/gltf_read.h) by
// tinygltf; OBJ is read by a small parser here (Debian's OpenMesh asserts,
// i.e. aborts, on some broken OBJ faces) and written by io/obj_writer.h
// (OpenMesh's drops vertex colours). The OpenMesh adapters copy straight
// between files and the plain TriangleMesh, never through a half-edge mesh, so
// non-manifold faces (marching-cubes and LOD output can have them) are
// neither dropped nor split.
#pragma once

#include "core/types.h"

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
};
std::size_t write_mesh(const std::string& path, const TriangleMesh& mesh, const MeshWriteOptions& options = {});

// Throws InputError unless write_mesh could write `path`: a known extension in
// an existing folder, and not a folder itself. Commands call it before long
// work, not after.
void check_mesh_output(const std::string& path);

}  // namespace scan2lod
