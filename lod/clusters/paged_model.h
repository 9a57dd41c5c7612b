// A model read page by page within a memory budget: the cluster hierarchy's
// clusters, groups and pages are read once (a few bytes a triangle), and a
// cut reads only the pages of the clusters it draws (lod/clusters/page_geometry.h),
// keeping the most recently used ones while they fit the budget. A cut read
// this way is the cut of the whole model: the same triangles over the same
// vertices, compacted the same way.
//
// Through the LOD face (lod/lod_model.h) nothing changes for the caller:
// open_paged_model() gives a LodModel whose cluster hierarchy holds no
// triangles and whose vertices are empty; LevelExtractor and compact_level
// read what they need through ClusterHierarchy::paged.
#pragma once

#include <scan2lod/lod/clusters/cluster_hierarchy.h>
#include <scan2lod/lod/clusters/page_geometry.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace scan2lod {

struct PageStats {
  std::uint64_t head_bytes = 0;     // read to open the model
  std::uint64_t pages_read = 0, page_bytes_read = 0;
  std::uint64_t resident_bytes = 0, peak_resident_bytes = 0;  // pages held in memory, as PageGeometry::bytes()
};

class ClusterPages {
 public:
  // `head` from read_model_pages_head(path), with a cluster hierarchy. The
  // pages held stay within `budget` bytes, but for one page larger than it.
  // Throws InputError naming the file when it cannot be opened.
  ClusterPages(std::string path, const ModelPagesHead& head, std::uint64_t budget);
  ~ClusterPages();
  ClusterPages(const ClusterPages&) = delete;
  ClusterPages& operator=(const ClusterPages&) = delete;

  std::size_t size() const { return extents_.size(); }
  // What page `p` takes in memory once read, known before reading it.
  std::uint64_t page_bytes(std::size_t p) const;
  const PageExtent& extent(std::size_t p) const { return extents_[p]; }
  // The page holding cluster `c`.
  std::size_t page_of(std::int32_t c) const;
  // Where page `p`'s triangles start in the hierarchy's numbering: cluster c's
  // lie in its page from c.first_triangle - first_triangle(page_of(c)) on.
  std::uint32_t first_triangle(std::size_t p) const { return page_first_triangle_[p]; }
  bool resident(std::size_t p) const { return slots_[p] >= 0; }

  // Page `p`'s geometry, read from the file unless held, after dropping the
  // least recently used pages that are not pinned until it fits the budget.
  // Throws InputError naming the file and the page when its bytes are
  // damaged. The reference holds until the next call that reads a page.
  const PageGeometry& page(std::size_t p);
  // Pinned pages are never dropped (the coarsest levels, which every view
  // falls back on); `p` is read first when not held.
  void pin(std::size_t p);
  std::uint64_t pinned_bytes() const { return pinned_bytes_; }
  // Reads page `p` if it fits by dropping only pages last used before
  // `used_before` (a count of clock()); true when it is held afterwards.
  bool prefetch(std::size_t p, std::uint64_t used_before);
  // Counts page uses: pages used from now on have a later stamp.
  std::uint64_t clock() const { return clock_; }

  // The LOD face's part (ClusterHierarchy::paged): the selected clusters'
  // triangles over the model's vertex numbers, as emit_clusters gives them,
  // and the vertices of the last emission's triangles as compact_level gives
  // them.
  void emit(const ClusterHierarchy& h, const std::vector<std::int32_t>& selected, std::vector<Triangle>* triangles);
  TriangleMesh compact(std::vector<Triangle> triangles) const;

  std::uint64_t budget() const { return budget_; }
  const PageStats& stats() const { return stats_; }
  Aabb bounds() const;                 // around every page's vertices
  std::uint64_t stored_triangles() const { return stored_triangles_; }

 private:
  bool drop_until_fits(std::uint64_t bytes, std::size_t keep, std::uint64_t used_before);
  void read(std::size_t p);

  std::string path_;
  int fd_ = -1;
  std::uint64_t pages_offset_ = 0, first_vertex_ = 0, vertex_count_ = 0;  // the hierarchy's vertices
  bool normals_ = false, colors_ = false;
  std::vector<PageExtent> extents_;
  std::vector<std::uint32_t> page_first_cluster_, page_first_triangle_, page_triangles_;
  std::uint64_t stored_triangles_ = 0;
  std::uint64_t budget_;
  // Held pages: slots_[p] indexes held_ (-1: not held).
  std::vector<std::int32_t> slots_;
  struct Held {
    std::size_t page;
    PageGeometry geometry;
    std::uint64_t last_use = 0;
    bool pinned = false;
  };
  std::vector<Held> held_;
  std::vector<std::int32_t> free_slots_;
  std::uint64_t clock_ = 0, pinned_bytes_ = 0;
  std::vector<std::uint8_t> blob_;  // a page's bytes as read, reused
  PageStats stats_;
  // The last emission's vertices: model vertex -> into last_.
  FlatHashMap emitted_{1024};
  TriangleMesh last_;
};

// `path` opened for cuts read page by page, with at most `budget` bytes of
// pages held; no value when the file has no pages to read (no cluster
// hierarchy, or written before format 4.6), which load_model reads whole.
// The model has no octree even when the file has one.
std::optional<LodModel> open_paged_model(const std::string& path, std::uint64_t budget);

}  // namespace scan2lod
