// One tile's content as a binary glTF (Khronos Group, *glTF 2.0
// Specification*, 2017), for 3D Tiles 1.1, which takes .glb content directly.
//
// 3D Tiles is z-up and turns glTF content from glTF's y-up to z-up (3D Tiles
// 1.1, §"glTF transforms"); the positions are written turned the other way,
// (x, y, z) -> (x, z, -y), so that the tileset lies in the model's own frame.
//
// Positions are normalized 16-bit integers on one grid for the whole tileset
// (KHR_mesh_quantization): every tile has the same node translation and
// scale, so a triangle two neighbouring tiles both hold has the same bits in
// each and draws at the same depth. Normals are normalized 16-bit integers,
// colours COLOR_0 as 8-bit. With `meshopt`, every buffer view is compressed
// with meshoptimizer's codecs (EXT_meshopt_compression, version 0 of the
// vertex codec and 1 of the index codec) and the uncompressed buffer is a
// fallback that holds no bytes. Vertices are put in cache order first
// (meshopt_optimizeVertexCache, then meshopt_optimizeVertexFetch), which the
// codecs compress better.
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/io/gltf_file.h>
#include <scan2lod/lod/octree/mc_octree.h>

#include <cstdint>
#include <string>
#include <vector>

namespace scan2lod {


struct TileGlbOptions {
  bool quantize = true;  // KHR_mesh_quantization; false: 32-bit floats
  bool meshopt = true;   // EXT_meshopt_compression
  std::string generator = "scan2lod";
};

struct TileGlb {
  std::vector<unsigned char> bytes;
  std::size_t vertices = 0, triangles = 0;
};

// The .glb of `triangles` (into `vertices`; only the vertices they use are
// written). `triangles` must not be empty and must name vertices of
// `vertices`; normals and colours are written when `vertices` has them.
TileGlb tile_glb(const VertexArray& vertices, const std::vector<Triangle>& triangles, const PositionGrid& grid,
                 const TileGlbOptions& options);

}  // namespace scan2lod
