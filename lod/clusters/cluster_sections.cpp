#include <scan2lod/lod/clusters/cluster_sections.h>

#include <scan2lod/lod/clusters/triangle_spool.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <thread>

#include <xxhash.h>

namespace scan2lod {

static_assert(sizeof(Cluster) == 16 && sizeof(GroupBound) == 20 && sizeof(ClusterPage) == 32 &&
                  sizeof(PageExtent) == 48,
              "cluster records must be packed for the .mco layout");

namespace {

// Whether the pages lie in the order of 'CTRI', each one run, covering it:
// what 'PGEO' is cut from as 'CTRI' streams past. (A hierarchy made by hand
// may not; its file then has no 'PGEO', and a paged reader reads it whole.)
bool pages_follow_triangles(const ClusterHierarchy& h) {
  std::uint64_t next = 0, cluster = 0;
  for (const ClusterPage& p : h.pages) {
    if (p.first_cluster != cluster || p.cluster_count == 0 || p.cluster_count > h.clusters.size() - cluster)
      return false;
    for (; cluster < std::uint64_t(p.first_cluster) + p.cluster_count; ++cluster) {
      const Cluster& c = h.clusters[cluster];
      if (c.first_triangle != next) return false;
      next += c.triangle_count;
    }
  }
  return cluster == h.clusters.size() && next == h.stored_triangles();
}

// Calls visit(page, triangles, count) page by page, the triangles from
// memory or streamed from the spool.
void for_each_page(const ClusterHierarchy& h,
                   const std::function<void(std::size_t, const Triangle*, std::size_t)>& visit) {
  auto triangles_of = [&h](std::size_t page) {
    const ClusterPage& p = h.pages[page];
    const Cluster& first = h.clusters[p.first_cluster];
    const Cluster& last = h.clusters[p.first_cluster + p.cluster_count - 1];
    return std::size_t(last.first_triangle) + last.triangle_count - first.first_triangle;
  };
  if (!h.spool) {
    for (std::size_t page = 0; page < h.pages.size(); ++page)
      visit(page, h.triangles.data() + h.clusters[h.pages[page].first_cluster].first_triangle, triangles_of(page));
    return;
  }
  std::vector<Triangle> pending;
  std::size_t page = 0, partial = 0;  // bytes of a triangle split between runs
  Triangle split;
  h.spool->read([&](const std::uint8_t* bytes, std::size_t n) {
    while (n > 0) {
      if (partial || n < sizeof(Triangle)) {
        const std::size_t take = std::min(n, sizeof(Triangle) - partial);
        std::memcpy(reinterpret_cast<std::uint8_t*>(split.data()) + partial, bytes, take);
        partial += take, bytes += take, n -= take;
        if (partial == sizeof(Triangle)) pending.push_back(split), partial = 0;
      } else {
        const std::size_t whole = n / sizeof(Triangle);
        const std::size_t at = pending.size();
        pending.resize(at + whole);
        std::memcpy(static_cast<void*>(pending.data() + at), bytes, whole * sizeof(Triangle));
        bytes += whole * sizeof(Triangle), n -= whole * sizeof(Triangle);
      }
      std::size_t used = 0;
      while (page < h.pages.size() && pending.size() - used >= triangles_of(page)) {
        visit(page, pending.data() + used, triangles_of(page));
        used += triangles_of(page);
        ++page;
      }
      pending.erase(pending.begin(), pending.begin() + std::ptrdiff_t(used));
    }
  });
}

// One page's encoding, as encode_pages() hands it over.
struct EncodedPage {
  std::size_t page = 0;
  const Triangle* triangles = nullptr;
  std::size_t count = 0;
  std::vector<Triangle> copy;  // a spooled hierarchy's: its buffer is gone after the visit
  std::vector<std::uint8_t> blob;
  Aabb box;
  std::uint64_t checksum = 0;
  bool encoded = false;
};

// Calls visit(page) for every page in order, encoded (PageEncoder), with its
// checksum. Pages are encoded a batch at a time on every core: encoding was
// 62 % and the pages' checksums 12 % of saving a 13 M-triangle model, on one
// core. Returns false, having stopped, when a page cannot be encoded.
bool encode_pages(const ClusterHierarchy& h, const VertexArray& vertices,
                  const std::function<void(const EncodedPage&)>& visit) {
  const std::size_t threads = std::max(1u, std::thread::hardware_concurrency());
  std::vector<EncodedPage> batch(8 * threads);  // reused: a fresh one each batch was page faults
  std::vector<PageEncoder> encoders(threads);
  std::size_t held = 0;
  bool ok = true;
  auto flush = [&] {
    auto work = [&](std::size_t t) {
      for (std::size_t i = t; i < held; i += threads) {
        EncodedPage& e = batch[i];
        e.encoded = encoders[t].encode(e.triangles, e.count, vertices, &e.blob, &e.box);
        if (e.encoded) e.checksum = model_checksum(e.blob.data(), e.blob.size());
      }
    };
    std::vector<std::thread> others;
    for (std::size_t t = 1; t < std::min(threads, held); ++t) others.emplace_back(work, t);
    work(0);
    for (std::thread& t : others) t.join();
    for (std::size_t i = 0; i < held && ok; ++i) {
      if (!batch[i].encoded) ok = false;
      else visit(batch[i]);
    }
    held = 0;
  };
  for_each_page(h, [&](std::size_t page, const Triangle* triangles, std::size_t count) {
    if (!ok) return;
    EncodedPage& e = batch[held++];
    e.page = page;
    e.count = count;
    e.triangles = triangles;
    if (h.spool) e.copy.assign(triangles, triangles + count), e.triangles = e.copy.data();
    if (held == batch.size()) flush();
  });
  if (held > 0 && ok) flush();
  return ok;
}
void check_pages(const SectionReader& file, ClusterHierarchy& h);

}  // namespace

std::vector<SectionRow> ClusterSections::rows() {
  return {
      {"CINF", true, [this](LodModel&) { return record(info_, 24); }, 3},
      {"CLUS", true, [](LodModel& m) { return array(m.clusters->clusters); }, 3},
      {"CTRI", true,
       [this](LodModel& m) {
         Payload p = array(m.clusters->triangles);
         // A hierarchy built in blocks may hold its triangles on disk.
         if (const TriangleSpool* spool = m.clusters->spool.get()) {
           p.count = spool->size();
           p.stream = [spool](const Emit& emit) { spool->read(emit); };
           p.stream_checksum = spool->checksum();
         }
         // Paged: the triangles stay in the file, read page by page from 'PGEO'.
         p.left_in_file = paged_;
         return p;
       },
       3},
      {"CGRP", true, [](LodModel& m) { return array(m.clusters->groups); }, 3},
      // 4.7 (and 3), optional: older readers rank the cuts by count with the errors.
      {"CGRK", false,
       [](LodModel& m) {
         Payload p = array(m.clusters->group_ranks);
         p.written = !m.clusters->group_ranks.empty();
         return p;
       },
       3},
      // 4.4, optional: older readers read the clusters whole; this one derives
      // the pages. A hierarchy made by hand, without pages, goes without.
      {"PAGE", false,
       [](LodModel& m) {
         Payload p = array(m.clusters->pages);
         p.written = !m.clusters->pages.empty();
         return p;
       },
       kPacked},
      // 4.6, optional: older readers, and load_model, read the clusters whole;
      // a paged reader (lod/clusters/paged_model.h) reads a page's geometry at a time.
      {"PGIX", false,
       [this](LodModel&) {
         Payload p = array(page_extents_);
         p.written = with_pages_;
         return p;
       },
       kPacked},
      {"PGEO", false,
       [this](LodModel&) {
         Payload p = streamed(page_bytes_);
         p.written = with_pages_;
         p.stream = [this](const Emit& emit) {
           encode_pages(*model_->clusters, model_->vertices,
                        [&](const EncodedPage& page) { emit(page.blob.data(), page.blob.size()); });
         };
         p.stream_checksum = pages_checksum_;
         return p;
       },
       kPacked},
  };
}

// Pages of geometry: encoded once here for their sizes and checksums, and
// again as they are written, so that they are never held whole.
void ClusterSections::prepare(const LodModel& model, std::uint32_t major) {
  const ClusterHierarchy& h = *model.clusters;
  model_ = &model;
  info_[0] = std::uint64_t(h.full_triangles);
  info_[1] = model.cluster_vertex_first;
  info_[2] = model.cluster_vertex_count;
  with_pages_ = major >= kPacked && !h.pages.empty() && pages_follow_triangles(h);
  if (!with_pages_) return;
  std::unique_ptr<XXH64_state_t, XXH_errorcode (*)(XXH64_state_t*)> hash(XXH64_createState(), XXH64_freeState);
  if (!hash) throw std::bad_alloc();
  XXH64_reset(hash.get(), 0);
  page_extents_.resize(h.pages.size());
  with_pages_ = encode_pages(h, model.vertices, [&](const EncodedPage& page) {
    PageExtent& e = page_extents_[page.page];
    e = {page_bytes_, std::uint32_t(page.blob.size()), 0, page.checksum, {}, {}};
    std::memcpy(&e.vertices, page.blob.data(), 4);
    for (int k = 0; k < 3; ++k) e.min[k] = page.box.min[k], e.max[k] = page.box.max[k];
    XXH64_update(hash.get(), page.blob.data(), page.blob.size());
    page_bytes_ += page.blob.size();
  });
  pages_checksum_ = XXH64_digest(hash.get());
  if (!with_pages_) page_extents_.clear(), page_bytes_ = 0;
}

// The cluster hierarchy's sections, checked so that no cut can read out of
// bounds: ranges inside their arrays, groups that exist, finite bounds.
void ClusterSections::decode(SectionReader& file, LodModel* model) {
  const FileSection& info = file.section("CINF");
  if (info.count != 1 || info.element_size != 24) file.bad("section 'CINF' must be one record of 24 bytes");
  const std::uint8_t* record = file.payload(info);
  const std::uint64_t full = get_u64(record), first = get_u64(record + 8), count = get_u64(record + 16);
  const std::size_t vertices = file.vertices();
  if (first > vertices || count > vertices - first)
    file.bad("the cluster hierarchy's vertices " + std::to_string(first) + "+" + std::to_string(count) + " lie outside the " +
        std::to_string(vertices) + " vertices");
  model->clusters.emplace();
  paged_ = file.paged();
  file.read_rows(rows(), model);
  ClusterHierarchy& h = *model->clusters;
  const std::uint64_t stored = paged_ ? file.section("CTRI").count : h.triangles.size();
  h.full_triangles = std::int64_t(std::min<std::uint64_t>(full, std::uint64_t(std::numeric_limits<std::int64_t>::max())));
  if (h.clusters.empty()) file.bad("the cluster hierarchy has no clusters");
  for (std::size_t i = 0; i < h.triangles.size(); ++i)
    for (std::int32_t v : h.triangles[i])
      if (v < std::int64_t(first) || std::uint64_t(v) >= first + count)
        file.bad("section 'CTRI': triangle " + std::to_string(i) + " names vertex " + std::to_string(v) + " outside " +
            std::to_string(first) + "+" + std::to_string(count));
  for (std::size_t g = 0; g < h.groups.size(); ++g) {
    const GroupBound& b = h.groups[g];
    if (!(std::isfinite(b.center[0]) && std::isfinite(b.center[1]) && std::isfinite(b.center[2]) &&
          std::isfinite(b.radius) && b.radius >= 0 && std::isfinite(b.error) && b.error > 0))
      file.bad("section 'CGRP': group " + std::to_string(g) + " needs a finite centre, radius >= 0 and error > 0");
  }
  const std::int64_t groups = std::int64_t(h.groups.size());
  const bool ranked = !h.group_ranks.empty();
  if (ranked && h.group_ranks.size() != h.groups.size())
    file.bad("section 'CGRK' has " + std::to_string(h.group_ranks.size()) + " ranks for " + std::to_string(groups) +
        " groups");
  for (std::size_t g = 0; g < h.group_ranks.size(); ++g)
    if (!(std::isfinite(h.group_ranks[g]) && h.group_ranks[g] > 0))
      file.bad("section 'CGRK': group " + std::to_string(g) + " needs a finite rank > 0");
  std::int64_t level0 = 0;
  for (std::size_t c = 0; c < h.clusters.size(); ++c) {
    const Cluster& cl = h.clusters[c];
    auto where = [c] { return "section 'CLUS': cluster " + std::to_string(c) + ": "; };
    if (cl.triangle_count == 0) file.bad(where() + "no triangles");
    if (std::uint64_t(cl.first_triangle) + cl.triangle_count > stored)
      file.bad(where() + "triangles " + std::to_string(cl.first_triangle) + "+" + std::to_string(cl.triangle_count) +
          " past the " + std::to_string(stored) + " of 'CTRI'");
    if (cl.own_group < -1 || cl.own_group >= groups || cl.parent_group < -1 || cl.parent_group >= groups)
      file.bad(where() + "group " + std::to_string(cl.own_group) + " or " + std::to_string(cl.parent_group) + " of " +
          std::to_string(groups));
    if (cl.own_group >= 0 && cl.own_group == cl.parent_group) file.bad(where() + "its own group is its parent");
    if ((cl.own_group < 0) != (cl.level == 0)) file.bad(where() + "level 0 and full detail (no own group) must agree");
    if (cl.own_group >= 0 && cl.parent_group >= 0 &&
        h.groups[std::size_t(cl.parent_group)].error < h.groups[std::size_t(cl.own_group)].error)
      file.bad(where() + "its parent group's error is below its own");
    if (ranked && cl.own_group >= 0 && cl.parent_group >= 0 &&
        h.group_ranks[std::size_t(cl.parent_group)] < h.group_ranks[std::size_t(cl.own_group)])
      file.bad(where() + "its parent group's rank is below its own");
    if (cl.own_group < 0) level0 += cl.triangle_count;
  }
  if (level0 != h.full_triangles)
    file.bad("the full-detail clusters hold " + std::to_string(level0) + " triangles, 'CINF' says " +
        std::to_string(h.full_triangles));
  check_pages(file, h);
  model->cluster_vertex_first = std::size_t(first);
  model->cluster_vertex_count = std::size_t(count);
}

namespace {

// Pages (4.4) must list the clusters in order, each page's triangles one run,
// and each page's error interval must hold its clusters' own and parent
// errors, so that a viewer that skips pages outside a threshold skips no
// cluster a cut draws. A file without them gets them derived.
void check_pages(const SectionReader& file, ClusterHierarchy& h) {
  if (h.pages.empty()) {
    h.pages = cluster_pages(h);
    return;
  }
  std::size_t next = 0;
  for (std::size_t i = 0; i < h.pages.size(); ++i) {
    const ClusterPage& p = h.pages[i];
    auto where = [i] { return "section 'PAGE': page " + std::to_string(i) + ": "; };
    if (p.first_cluster != next || p.cluster_count == 0 || p.cluster_count > h.clusters.size() - next)
      file.bad(where() + "clusters " + std::to_string(p.first_cluster) + "+" + std::to_string(p.cluster_count) +
          " do not follow on from cluster " + std::to_string(next) + " of " + std::to_string(h.clusters.size()));
    if (!(std::isfinite(p.center[0]) && std::isfinite(p.center[1]) && std::isfinite(p.center[2]) && p.radius >= 0 &&
          p.min_error >= 0 && p.min_error <= p.max_error))
      file.bad(where() + "needs a finite centre, radius >= 0 and 0 <= min error <= max error");
    for (std::size_t c = p.first_cluster; c < std::size_t(p.first_cluster) + p.cluster_count; ++c) {
      const Cluster& cl = h.clusters[c];
      if (c > p.first_cluster &&
          h.clusters[c - 1].first_triangle + h.clusters[c - 1].triangle_count != cl.first_triangle)
        file.bad(where() + "cluster " + std::to_string(c) + "'s triangles do not follow on from the one before");
      const float own = cl.own_group < 0 ? 0.f : h.groups[std::size_t(cl.own_group)].error;
      const float parent = cl.parent_group < 0 ? std::numeric_limits<float>::infinity()
                                               : h.groups[std::size_t(cl.parent_group)].error;
      if (own < p.min_error || parent > p.max_error)
        file.bad(where() + "cluster " + std::to_string(c) + "'s errors lie outside the page's");
    }
    next += p.cluster_count;
  }
  if (next != h.clusters.size())
    file.bad("section 'PAGE': the pages hold " + std::to_string(next) + " of the " + std::to_string(h.clusters.size()) +
        " clusters");
}

}  // namespace

// 'PGIX' must lay the pages end to end over 'PGEO', each within what its
// triangles can need, with a finite box.
void ClusterSections::check_page_extents(const SectionReader& file, const ClusterHierarchy& h) const {
  const std::vector<PageExtent>& extents = page_extents_;
  if (extents.size() != h.pages.size())
    file.bad("section 'PGIX' has " + std::to_string(extents.size()) + " pages, 'PAGE' " + std::to_string(h.pages.size()));
  std::uint64_t next = 0;
  for (std::size_t i = 0; i < extents.size(); ++i) {
    const PageExtent& e = extents[i];
    const std::string where = "section 'PGIX': page " + std::to_string(i) + ": ";
    if (e.offset != next || e.bytes % 8 != 0)
      file.bad(where + "its " + bytes_text(e.bytes) + " at " + std::to_string(e.offset) + " do not follow on from " +
          std::to_string(next));
    next += e.bytes;
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(e.min[k]) || !std::isfinite(e.max[k]) || e.min[k] > e.max[k])
        file.bad(where + "needs a finite box");
  }
  if (next != file.section("PGEO").length)
    file.bad("section 'PGIX': the pages hold " + bytes_text(next) + ", 'PGEO' " + bytes_text(file.section("PGEO").length));
}
}  // namespace scan2lod
