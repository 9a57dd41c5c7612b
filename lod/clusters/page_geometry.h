// One page of the cluster hierarchy as the model file stores it for reading
// page by page (section 'PGEO', lod/model_file.h): the page's triangles over
// a vertex table of its own, so that one read gives everything the page
// draws, as Nexus stores its patches (Ponchio, *Multiresolution structures
// for interactive visualization of very large 3D datasets*, 2008). Each local
// vertex keeps the model's vertex number, so that cuts read page by page weld
// across pages and give the same mesh as the whole model.
//
// Layout (little-endian), 8-byte aligned:
//   u32 V vertices, u32 T triangles, u32 flags (1 normals, 2 colours,
//   4 16-bit indices), u32 0
//   u32 model vertex[V]       in the order the page's triangles first use them
//   f32 position[V][3]
//   f32 normal[V][3]          with flag 1
//   u8  colour[V][3]          with flag 2, padded to 4 bytes
//   u16 or u32 index[T][3]    into the local vertices, padded to 8 bytes
#pragma once

#include <scan2lod/core/flat_hash.h>
#include <scan2lod/core/types.h>
#include <scan2lod/lod/octree/mc_octree.h>

#include <cstdint>
#include <string>
#include <vector>

namespace scan2lod {

// Where one page lies in section 'PGEO': one record of 48 bytes a page in
// section 'PGIX', in page order.
struct PageExtent {
  std::uint64_t offset;    // from the start of 'PGEO', a multiple of 8
  std::uint32_t bytes;
  std::uint32_t vertices;  // its local vertices
  std::uint64_t checksum;  // XXH64 of its bytes
  float min[3], max[3];    // the box around its vertices
};

struct PageGeometry {
  std::vector<std::uint32_t> model_vertices;  // local vertex -> the model's
  std::vector<Vec3f> positions, normals;      // normals: empty or one per vertex
  std::vector<Rgb> colors;                    // empty or one per vertex
  std::vector<Triangle> triangles;            // local indices, the page's clusters in order

  std::size_t bytes() const;  // held in memory
};

// Encodes pages one after another, reusing its scratch space.
class PageEncoder {
 public:
  // `triangles` index `vertices`. Writes the page to `blob` (cleared first)
  // and the box around its vertices to `box`; false, writing nothing, when
  // a triangle names a vertex outside `vertices` (a model made by hand).
  bool encode(const Triangle* triangles, std::size_t count, const VertexArray& vertices,
              std::vector<std::uint8_t>* blob, Aabb* box);

 private:
  FlatHashMap local_{1024};
  std::vector<std::uint32_t> model_vertices_;
  std::vector<Triangle> local_triangles_;
};

// Reads a page written by PageEncoder into `page`. Returns an empty string,
// or what is wrong: sizes that disagree with `bytes`, `triangles` or each
// other, flags that disagree with `normals`/`colors`, a local index past the
// vertices, or a model vertex outside [first_vertex, first_vertex + vertex_count).
std::string decode_page(const std::uint8_t* blob, std::size_t bytes, std::size_t triangles, bool normals,
                        bool colors, std::uint64_t first_vertex, std::uint64_t vertex_count, PageGeometry* page);

}  // namespace scan2lod
