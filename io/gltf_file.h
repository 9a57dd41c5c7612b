// glTF 2.0 output (Khronos Group, *glTF 2.0 Specification*, 2017), written by
// tinygltf: `.glb` (binary, one file) or `.gltf` (JSON with the buffer
// embedded as a data URI, still one file).
//
// A mesh is one node with one triangle primitive: POSITION, NORMAL and COLOR_0
// when present, and a material that is not metallic (glTF's default material
// is, which renders vertex colours dark). By default positions are stored as
// normalized 16-bit integers under the node's translation and uniform scale,
// and normals as normalized 16-bit integers (KHR_mesh_quantization): 16 bytes
// a vertex instead of 24; the position step is 1/65534 of the longest side of
// the bounding box.
//
// A chain of levels (MSFT_lod) shares one set of vertex arrays: every level is
// an index buffer into it, the finest level's node lists the coarser nodes,
// and its extras.MSFT_screencoverage gives, per level, the smallest share of
// the screen at which that level is still drawn.
#pragma once

#include <scan2lod/core/types.h>

#include <string>
#include <vector>

namespace scan2lod {

// The grid quantized positions are stored on (KHR_mesh_quantization, as
// normalized int16): position = centre + scale * stored / 32767 in the
// model's frame. Uniform, so that normals need no correction and the shape
// keeps its proportions.
struct PositionGrid {
  Vec3f centre = Vec3f::Zero();
  float scale = 1;
  float step() const { return scale / 32767.f; }
};

// The grid for positions inside `box`: its step is about 1/65534 of the
// box's longest side.
PositionGrid position_grid(const Aabb& box);

struct GltfOptions {
  bool quantize = true;        // KHR_mesh_quantization; false: 32-bit floats
  std::string generator;       // asset.generator, e.g. "scan2lod 0.1.0"
  // The point of the file's frame the positions are relative to (file frame =
  // origin + position, io/mesh_file.h): every level's node is translated by
  // it, a double in the JSON, while the float positions stay local and keep
  // their precision. Zero writes no translation beyond the quantization's.
  Vec3d origin = Vec3d::Zero();
};

// One level of a chain: triangles into the shared vertices, its name, and the
// screen coverage (0 to 1) from which on it is drawn.
struct GltfLevel {
  const std::vector<Triangle>* triangles = nullptr;
  std::string name;
  double screen_coverage = 0;
};

// Writes `mesh` (its triangles as the only level) to `path`, .glb or .gltf,
// with only the vertices they use.
// Throws InputError for another extension, an inconsistent mesh or a failed
// write; output goes through a temporary file renamed into place.
void write_gltf(const std::string& path, const TriangleMesh& mesh, const GltfOptions& options = {});

// Writes `levels` over the vertex arrays of `vertices` (its triangles are not
// read) as one MSFT_lod chain, finest level first. Screen coverages must not
// increase along the chain. One level writes a plain mesh. Vertices that no
// level uses are left out (io/used_vertices.h).
void write_gltf_chain(const std::string& path, const TriangleMesh& vertices, const std::vector<GltfLevel>& levels,
                      const GltfOptions& options = {});

// True for .glb and .gltf (any case).
bool is_gltf_path(const std::string& path);

}  // namespace scan2lod
