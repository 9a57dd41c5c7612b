#include <scan2lod/lod/clusters/paged_model.h>

#include <scan2lod/core/error.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include <fcntl.h>
#include <unistd.h>

namespace scan2lod {

ClusterPages::ClusterPages(std::string path, const ModelPagesHead& head, std::uint64_t budget)
    : path_(std::move(path)),
      pages_offset_(head.pages_offset),
      first_vertex_(head.model.cluster_vertex_first),
      vertex_count_(head.model.cluster_vertex_count),
      normals_(head.normals),
      colors_(head.colors),
      extents_(head.extents),
      budget_(budget) {
  const ClusterHierarchy& h = *head.model.clusters;
  fd_ = ::open(path_.c_str(), O_RDONLY);
  if (fd_ < 0) throw InputError(path_, std::string("cannot read the model: ") + std::strerror(errno));
  for (const ClusterPage& p : h.pages) {
    const Cluster& first = h.clusters[p.first_cluster];
    const Cluster& last = h.clusters[p.first_cluster + p.cluster_count - 1];
    page_first_cluster_.push_back(p.first_cluster);
    page_first_triangle_.push_back(first.first_triangle);
    page_triangles_.push_back(last.first_triangle + last.triangle_count - first.first_triangle);
    stored_triangles_ += page_triangles_.back();
  }
  slots_.assign(extents_.size(), -1);
  stats_.head_bytes = head.bytes_read;
}

ClusterPages::~ClusterPages() {
  if (fd_ >= 0) ::close(fd_);
}

std::uint64_t ClusterPages::page_bytes(std::size_t p) const {
  const std::uint64_t v = extents_[p].vertices;
  return v * (4 + 12 + (normals_ ? 12 : 0) + (colors_ ? 3 : 0)) + std::uint64_t(page_triangles_[p]) * 12;
}

std::size_t ClusterPages::page_of(std::int32_t c) const {
  const auto it = std::upper_bound(page_first_cluster_.begin(), page_first_cluster_.end(), std::uint32_t(c));
  return std::size_t(it - page_first_cluster_.begin()) - 1;
}

Aabb ClusterPages::bounds() const {
  Aabb box;
  for (const PageExtent& e : extents_) {
    box.extend(Vec3f(e.min[0], e.min[1], e.min[2]));
    box.extend(Vec3f(e.max[0], e.max[1], e.max[2]));
  }
  return box;
}

bool ClusterPages::drop_until_fits(std::uint64_t bytes, std::size_t keep, std::uint64_t used_before) {
  while (stats_.resident_bytes + bytes > budget_) {
    std::int32_t oldest = -1;
    for (std::size_t s = 0; s < held_.size(); ++s) {
      const Held& h = held_[s];
      if (h.page == std::size_t(-1) || h.pinned || h.page == keep || h.last_use >= used_before) continue;
      if (oldest < 0 || h.last_use < held_[std::size_t(oldest)].last_use) oldest = std::int32_t(s);
    }
    if (oldest < 0) return false;  // only pinned (or protected) pages left
    Held& h = held_[std::size_t(oldest)];
    stats_.resident_bytes -= page_bytes(h.page);
    slots_[h.page] = -1;
    h.page = std::size_t(-1);
    h.geometry = PageGeometry();
    free_slots_.push_back(oldest);
  }
  return true;
}

const PageGeometry& ClusterPages::page(std::size_t p) {
  if (slots_[p] < 0) {
    // Over the budget only when pinned pages leave no room: this one is held anyway.
    drop_until_fits(page_bytes(p), p, ~std::uint64_t(0));
    read(p);
  }
  Held& h = held_[std::size_t(slots_[p])];
  h.last_use = ++clock_;
  return h.geometry;
}

bool ClusterPages::prefetch(std::size_t p, std::uint64_t used_before) {
  if (slots_[p] >= 0) return true;
  if (!drop_until_fits(page_bytes(p), p, used_before)) return false;
  read(p);
  // Kept through this round of prefetching; older than what the next view uses.
  held_[std::size_t(slots_[p])].last_use = used_before;
  return true;
}

void ClusterPages::read(std::size_t p) {
  const PageExtent& e = extents_[p];
  blob_.resize(e.bytes);
  const std::string where = "page " + std::to_string(p) + " of section 'PGEO': ";
  std::uint64_t offset = pages_offset_ + e.offset;
  for (std::size_t got = 0; got < e.bytes;) {
    const ssize_t r = ::pread(fd_, blob_.data() + got, e.bytes - got, off_t(offset + got));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) throw InputError(path_, where + "cannot be read (truncated or gone)");
    got += std::size_t(r);
  }
  if (model_checksum(blob_.data(), blob_.size()) != e.checksum)
    throw InputError(path_, where + "checksum mismatch (damaged file)");
  std::int32_t slot;
  if (!free_slots_.empty()) {
    slot = free_slots_.back();
    free_slots_.pop_back();
  } else {
    slot = std::int32_t(held_.size());
    held_.emplace_back();
  }
  Held& h = held_[std::size_t(slot)];
  const std::string wrong = decode_page(blob_.data(), blob_.size(), page_triangles_[p], normals_, colors_,
                                        first_vertex_, vertex_count_, &h.geometry);
  if (!wrong.empty() || h.geometry.model_vertices.size() != e.vertices) {
    h.page = std::size_t(-1);
    h.geometry = PageGeometry();
    free_slots_.push_back(slot);
    throw InputError(path_, "inconsistent model: " + where + (wrong.empty() ? "vertex count disagrees with 'PGIX'" : wrong));
  }
  h.page = p;
  h.last_use = 0;
  h.pinned = false;
  slots_[p] = slot;
  ++stats_.pages_read;
  stats_.page_bytes_read += e.bytes;
  stats_.resident_bytes += page_bytes(p);
  stats_.peak_resident_bytes = std::max(stats_.peak_resident_bytes, stats_.resident_bytes);
}

void ClusterPages::pin(std::size_t p) {
  page(p);
  Held& h = held_[std::size_t(slots_[p])];
  if (!h.pinned) pinned_bytes_ += page_bytes(p);
  h.pinned = true;
}

void ClusterPages::emit(const ClusterHierarchy& h, const std::vector<std::int32_t>& selected,
                        std::vector<Triangle>* triangles) {
  emitted_.clear();
  last_ = TriangleMesh();
  std::size_t count = 0;
  for (const std::int32_t c : selected) count += h.clusters[std::size_t(c)].triangle_count;
  triangles->reserve(triangles->size() + count);
  emitted_.reserve(count / 2 + 16);
  for (std::size_t i = 0; i < selected.size();) {
    // The selected clusters of one page, read once.
    const std::size_t p = page_of(selected[i]);
    const PageGeometry& g = page(p);
    for (; i < selected.size() && page_of(selected[i]) == p; ++i) {
      const Cluster& cl = h.clusters[std::size_t(selected[i])];
      const std::size_t first = cl.first_triangle - first_triangle(p);
      for (std::size_t t = first; t < first + cl.triangle_count; ++t) {
        Triangle out;
        for (int k = 0; k < 3; ++k) {
          const std::int32_t local = g.triangles[t][k];
          const std::uint32_t v = g.model_vertices[std::size_t(local)];
          out[k] = std::int32_t(v);
          const std::int32_t next = std::int32_t(last_.positions.size());
          if (emitted_.insert(v, next) == next) {
            last_.positions.push_back(g.positions[std::size_t(local)]);
            if (normals_) last_.normals.push_back(g.normals[std::size_t(local)]);
            if (colors_) last_.colors.push_back(g.colors[std::size_t(local)]);
          }
        }
        triangles->push_back(out);
      }
    }
  }
}

TriangleMesh ClusterPages::compact(std::vector<Triangle> triangles) const {
  TriangleMesh mesh;
  FlatHashMap renumber(triangles.size() / 2 + 16);
  for (Triangle& t : triangles)
    for (std::int32_t& v : t) {
      const std::int32_t from = emitted_.find(std::uint64_t(std::uint32_t(v)));
      if (from < 0) throw std::logic_error("ClusterPages::compact: a vertex the last cut did not emit");
      const std::int32_t next = std::int32_t(mesh.positions.size());
      const std::int32_t id = renumber.insert(std::uint64_t(std::uint32_t(v)), next);
      if (id == next) {
        mesh.positions.push_back(last_.positions[std::size_t(from)]);
        if (normals_) mesh.normals.push_back(last_.normals[std::size_t(from)]);
        if (colors_) mesh.colors.push_back(last_.colors[std::size_t(from)]);
      }
      v = id;
    }
  mesh.triangles = std::move(triangles);
  return mesh;
}

std::optional<LodModel> open_paged_model(const std::string& path, std::uint64_t budget) {
  ModelPagesHead head = read_model_pages_head(path);
  if (!head.model.clusters) return std::nullopt;
  auto pages = std::make_shared<ClusterPages>(path, head, budget);
  std::optional<LodModel> model(std::in_place);
  std::swap(*model, head.model);
  model->clusters->paged = std::move(pages);
  return model;
}

}  // namespace scan2lod
