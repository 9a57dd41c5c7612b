// Two mesh files compared as `scan2lod compare` compares them, for the
// command line and the Python package alike: both read into one frame, then
// measured with compare_surfaces() (measure/surface_distance.h), errors
// naming both files.
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/measure/surface_distance.h>

#include <string>

namespace scan2lod {

struct MeshPair {
  TriangleMesh a, b;
};

// Reads `a` and `b` (io/mesh_file.h, read_mesh) about a local origin each and
// moves b to a's origin, the offset taken in double: georeferenced meshes
// (double PLY, OBJ text at UTM) are compared in one frame without float steps
// of a metre. Throws InputError naming the file that cannot be read.
MeshPair read_in_one_frame(const std::string& a, const std::string& b);

// compare_surfaces(a, b, options), its InputError naming "A vs B" (the
// library below cannot know the file names; a user needs them).
SurfaceComparison compare_named(const TriangleMesh& a, const TriangleMesh& b, const CompareOptions& options,
                                const std::string& name_a, const std::string& name_b);

}  // namespace scan2lod
