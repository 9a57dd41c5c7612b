// glTF 2.0 input (Khronos Group, *glTF 2.0 Specification*, 2017), read by
// tinygltf: the triangles a viewer would draw from a `.glb` or `.gltf` file,
// as one plain TriangleMesh in the scene's frame.
//
// The default scene (the first, if none is named default; every root node if
// the file has no scene) is walked from its root nodes down, and every
// triangle primitive of every node's mesh is taken with the node's world
// transform applied to positions and normals (a mirroring transform flips the
// winding back to counter-clockwise). Nodes outside the scene are not read:
// an MSFT_lod chain, as io/gltf_file.h writes it, reads as its finest level.
//
// Attributes may be 32-bit floats or, under KHR_mesh_quantization, normalized
// or plain 8- and 16-bit integers, interleaved or not, sparse or not.
#pragma once

#include <scan2lod/core/types.h>

#include <string>

namespace scan2lod {

// Reads the mesh the default scene of the .glb or .gltf file `path` draws.
//   positions  every vertex that a triangle uses, in the scene's frame, in the
//              file's order, primitive by primitive; primitives that share
//              their attribute accessors under one node share their vertices
//   triangles  from TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN primitives,
//              indexed or not; POINTS and LINES primitives are skipped
//   normals    NORMAL, unit length, when every primitive read has it, else empty
//   colors     COLOR_0 (RGB or RGBA, float or normalized integers; alpha is
//              dropped), when every primitive read has it, else empty
// The container is recognised by its content (GLB magic or JSON), not the
// extension. Buffers may be embedded, in the GLB's binary chunk, or files
// beside a .gltf; images are never decoded.
// Throws InputError naming the file when it cannot be parsed, requires an
// extension that changes geometry other than KHR_mesh_quantization (naming
// it; extensions for materials, textures and lights are ignored), has an
// accessor that reaches outside its buffer or has a type its attribute may
// not have, an index that names no vertex, or no triangle in its scene.
// Thread-safe.
TriangleMesh read_gltf(const std::string& path);

// The same about a local origin (file frame = *origin + position, summed in
// double; io/local_origin.h chooses it): the node transforms are applied in
// double, so that a mesh placed by a large translation (a georeferenced one,
// io/gltf_file.h) keeps its floats' precision. *origin is zero, and the mesh
// the one above, when floats hold the scene's coordinates.
TriangleMesh read_gltf(const std::string& path, Vec3d* origin);

}  // namespace scan2lod
