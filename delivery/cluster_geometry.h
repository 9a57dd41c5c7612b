// A cluster's triangles and the vertices they name, read one way from a
// model in memory (load_model: the hierarchy's triangles over the model's
// vertices) and from one read page by page (open_paged_model: each page's
// triangles over a vertex table of its own, lod/clusters/page_geometry.h). The tile
// planner (delivery/tile_tree.h) reads geometry through this alone, so that
// one planner serves both and gives both the same tiles.
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/lod/lod_model.h>

#include <cstddef>
#include <cstdint>

namespace scan2lod {

class ClusterPages;

// One cluster's triangles over a vertex table: the model's, or its page's.
struct ClusterTriangles {
  const Triangle* triangles = nullptr;  // `count` of them, indexing the tables below
  std::size_t count = 0;
  const Vec3f* positions = nullptr;
  const Vec3f* normals = nullptr;       // null when the model has none
  const Rgb* colors = nullptr;          // null when the model has none
  // Index -> the model's vertex number, which names one vertex across
  // clusters and pages; null when the indices are the model's numbers.
  const std::uint32_t* model_vertices = nullptr;

  std::uint32_t model_vertex(std::int32_t i) const {
    return model_vertices ? model_vertices[i] : std::uint32_t(i);
  }
};

class ClusterGeometry {
 public:
  // `model` (kept by reference) has a cluster hierarchy whose triangles are
  // in memory or read page by page, not spooled.
  explicit ClusterGeometry(const LodModel& model);

  // Cluster `c`'s triangles. They hold until the next call, which may drop
  // the page they lie in.
  ClusterTriangles triangles(std::int32_t c);

 private:
  const LodModel& model_;
  ClusterPages* pages_;  // null: the model is in memory
};

}  // namespace scan2lod
