// PLY and OFF with positions in double, for meshes in a georeferenced frame
// (io/mesh_file.h): OpenMesh 9.0, which reads and writes these formats
// otherwise, holds positions as floats only, so these are written here and
// their positions read back here, in double, beside OpenMesh's reading of
// everything else.
#pragma once

#include <scan2lod/core/types.h>

#include <cstddef>
#include <string>
#include <vector>

namespace scan2lod {

// Writes `mesh` to `file` as binary little-endian PLY in the layout OpenMesh
// writes (vertex x y z, nx ny nz when the mesh has normals, uchar red green
// blue when it has colours; face `list uchar int vertex_indices`), but with
// `property double x/y/z` holding origin + position, summed in double.
// Throws InputError naming `name` when the file cannot be written.
void write_ply_in_frame(const std::string& file, const std::string& name, const TriangleMesh& mesh,
                        const Vec3d& origin);

// Writes `mesh` to `file` as ASCII OFF in the layout OpenMesh writes ([C][N]OFF,
// normals as floats, colours as RGBA with alpha 255), with origin + position
// summed in double and printed with the shortest digits that read back as it.
// Throws InputError naming `name` when the file cannot be written.
void write_off_in_frame(const std::string& file, const std::string& name, const TriangleMesh& mesh,
                        const Vec3d& origin);

// The vertex positions of the PLY file `path`, in double, when its x, y or z
// is a `double` (or `float64`) property, else empty (a float is then what the
// file holds). The header must have passed read_mesh's checks (vertex
// properties without lists, elements before `vertex` of fixed size).
// Throws InputError naming the file when the body ends early or holds a value
// that is not a number.
std::vector<Vec3d> read_ply_double_positions(const std::string& path);

// The first `vertices` positions of the ASCII OFF file `path`, in double
// (each vertex on a line of its own, x y z first); empty for binary OFF,
// which holds floats. Throws InputError naming the file and line when a
// vertex line does not start with three numbers.
std::vector<Vec3d> read_off_double_positions(const std::string& path, std::size_t vertices);

}  // namespace scan2lod
