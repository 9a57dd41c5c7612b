// VTK's XML PolyData (.vtp), read and written through VTK. Apart from the
// other mesh formats (io/mesh_file.h dispatches to it) so that a program
// that never meets a .vtp file maps no VTK library: the model-reading
// commands run without it (cli/lean_main.cpp).
#pragma once

#include <scan2lod/core/types.h>

#include <string>
#include <vector>

namespace scan2lod {

// The mesh of a .vtp file; with `exact`, its points in double as well (VTK
// hands them over as doubles). Throws InputError naming the file.
TriangleMesh read_vtp(const std::string& path, std::vector<Vec3d>* exact);

// Writes `mesh` to `tmp` (renamed to final_path by the caller): raw
// appended binary, points in Float64 about `origin` when it is not zero.
// Throws InputError naming final_path.
void write_vtp(const std::string& tmp, const std::string& final_path, const TriangleMesh& mesh, const Vec3d& origin);

}  // namespace scan2lod
