// Wavefront OBJ output with vertex colours as the common `v x y z r g b`
// extension (0..1, as MeshLab, Blender and read_mesh read them). OpenMesh's
// OBJ writer (Debian 12, 9.0) turns colours into per-face materials in a
// second .mtl file, so colours would be lost from a single-file output.
#pragma once

#include <scan2lod/core/types.h>

#include <string>

namespace scan2lod {

// Writes `mesh` to `file` as ASCII OBJ: `v` (with r g b when the mesh has
// colours), `vn` when it has normals, and 1-based `f a b c` / `f a//a ...`.
// Floats keep 9 significant digits, which round-trip exactly. With a non-zero
// `origin`, `v` holds origin + position, summed in double and printed with
// the shortest digits that round-trip the double (at most 17). Throws
// InputError naming `name` when the file cannot be written.
void write_obj(const std::string& file, const std::string& name, const TriangleMesh& mesh,
               const Vec3d& origin = Vec3d::Zero());

}  // namespace scan2lod
