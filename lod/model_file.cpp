#include <scan2lod/lod/model_file.h>

#include <scan2lod/core/error.h>
#include <scan2lod/io/atomic_file.h>
#include <scan2lod/io/file_extension.h>
#include <scan2lod/lod/clusters/page_geometry.h>
#include <scan2lod/lod/clusters/triangle_spool.h>
#include <scan2lod/lod/octree/model_pack.h>
#include <scan2lod/lod/octree/transition.h>
#include <scan2lod/reconstruct/cube_table.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <system_error>
#include <thread>

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>
#include <xxhash.h>

namespace scan2lod {

// The arrays go to disk as they lie in memory; that is the file's byte order
// only on little-endian hosts (every machine this project targets).
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the .mco reader and writer assume a little-endian host");
static_assert(sizeof(Vec3f) == 12 && sizeof(Triangle) == 12 && sizeof(Rgb) == 3 &&
                  sizeof(std::array<std::int32_t, 12>) == 48 &&
                  sizeof(std::array<std::int32_t, kSubEdges>) == 4 * kSubEdges &&
                  sizeof(std::array<std::int32_t, 27>) == 108,
              "McOctree element types must be packed for the .mco layout");
static_assert(sizeof(Cluster) == 16 && sizeof(GroupBound) == 20 && sizeof(ClusterPage) == 32 &&
                  sizeof(PageExtent) == 48,
              "cluster records must be packed for the .mco layout");

namespace {

constexpr char kMagic[8] = {'S', 'C', 'A', 'N', '2', 'L', 'O', 'D'};
constexpr std::size_t kHeaderBytes = 40;
constexpr std::size_t kEntryBytes = 48;
constexpr std::size_t kGridRecordBytes = 48;
constexpr std::uint32_t kRequired = 1;

constexpr std::uint32_t fourcc(const char (&s)[5]) {
  return std::uint32_t(std::uint8_t(s[0])) | std::uint32_t(std::uint8_t(s[1])) << 8 |
         std::uint32_t(std::uint8_t(s[2])) << 16 | std::uint32_t(std::uint8_t(s[3])) << 24;
}

std::string tag_name(std::uint32_t tag) {
  std::string s;
  for (int i = 0; i < 4; ++i) {
    const char c = char((tag >> (8 * i)) & 0xff);
    if (c < 0x20 || c > 0x7e) {
      char hex[16];
      std::snprintf(hex, sizeof hex, "0x%08x", tag);
      return hex;
    }
    s += c;
  }
  return "'" + s + "'";
}

void put_u32(std::uint8_t* p, std::uint32_t v) { std::memcpy(p, &v, 4); }
void put_u64(std::uint8_t* p, std::uint64_t v) { std::memcpy(p, &v, 8); }
std::uint32_t get_u32(const std::uint8_t* p) {
  std::uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}
std::uint64_t get_u64(const std::uint8_t* p) {
  std::uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}


// What the sections hold besides the model's arrays as they lie in memory:
// the records (the grid, the pinned count, the cluster hierarchy's info) and,
// from format 4 on, the octree packed (lod/octree/model_pack.h).
struct Records {
  std::uint8_t grid[kGridRecordBytes] = {};
  double origin[3] = {0, 0, 0};
  std::uint64_t pinned = 0;
  std::uint64_t cluster_info[3] = {0, 0, 0};
  PackedOctree packed;
  std::vector<PageExtent> page_extents;  // 'PGIX'
  std::uint64_t page_bytes = 0;          // 'PGEO''s length, streamed (never held whole)
};

// A section's payload in memory: element size, count and bytes, and for an
// array how to size it before reading into it.
struct Payload {
  std::uint32_t element_size = 0;
  std::uint64_t count = 0;
  void* data = nullptr;
  void* (*resize)(void* vector, std::uint64_t count) = nullptr;  // null for a record
  void* vector = nullptr;
};

template <class T, class Allocator>
Payload array(std::vector<T, Allocator>& v) {
  return {std::uint32_t(sizeof(T)), std::uint64_t(v.size()), static_cast<void*>(v.data()),
          [](void* vector, std::uint64_t count) -> void* {
            auto& v = *static_cast<std::vector<T, Allocator>*>(vector);
            resize_for_load(&v, count);
            return static_cast<void*>(v.data());
          },
          &v};
}

template <class T>
Payload record(T* r, std::size_t bytes) {
  return {std::uint32_t(bytes), 1, static_cast<void*>(r)};
}

// A section written from a stream and never read into memory by load_model.
Payload streamed(std::uint64_t bytes) { return {1, bytes, nullptr}; }

// Which structure a section belongs to: the shared vertices are always
// written, the octree's and the clusters' sections when the model has them.
enum class Part { kVertices, kOctree, kClusters };

struct SectionSpec {
  char tag[5];
  Part part;
  bool required;  // flags bit 0
  Payload (*payload)(LodModel& model, Records& records);
  std::uint32_t first_major = 2, last_major = kModelFormatMajor;  // the formats that hold it

  bool in(std::uint32_t major) const { return major >= first_major && major <= last_major; }
};

constexpr std::uint32_t kUnpacked = 3;  // the last format that stored the octree's arrays whole
constexpr std::uint32_t kPacked = 4;    // the first that packs them

OctreeNodes& nodes_of(LodModel& m) { return m.octree->tree.nodes; }
OctreeTransitions& transitions_of(LodModel& m) { return m.octree->tree.transitions; }
OctreePatches& patches_of(LodModel& m) { return m.octree->tree.patches; }

// Every section the format knows, in the order the writer lays them out
// (model_file.h describes each). Encoding and decoding both walk this table.
const SectionSpec kSections[] = {
    {"POSN", Part::kVertices, true, [](LodModel& m, Records&) { return array(m.vertices.positions); }},
    {"NRML", Part::kVertices, true, [](LodModel& m, Records&) { return array(m.vertices.normals); }},
    {"COLR", Part::kVertices, true, [](LodModel& m, Records&) { return array(m.vertices.colors); }},
    // 4.5, optional: older readers give levels about the origin.
    {"ORGN", Part::kVertices, false, [](LodModel&, Records& r) { return record(r.origin, 24); }, kPacked},
    {"GRID", Part::kOctree, true, [](LodModel&, Records& r) { return record(r.grid, kGridRecordBytes); }},
    {"KEYS", Part::kOctree, true, [](LodModel& m, Records&) { return array(nodes_of(m).keys); }, 2, kUnpacked},
    {"LEVL", Part::kOctree, true, [](LodModel& m, Records&) { return array(nodes_of(m).levels); }, 2, kUnpacked},
    {"PRNT", Part::kOctree, true, [](LodModel& m, Records&) { return array(nodes_of(m).parents); }, 2, kUnpacked},
    {"FCHD", Part::kOctree, true, [](LodModel& m, Records&) { return array(nodes_of(m).first_child); }, 2, kUnpacked},
    {"NCHD", Part::kOctree, true, [](LodModel& m, Records&) { return array(nodes_of(m).child_counts); }, 2, kUnpacked},
    {"CHLD", Part::kOctree, true, [](LodModel&, Records& r) { return array(r.packed.child_masks); }, kPacked},
    {"CASE", Part::kOctree, true, [](LodModel& m, Records&) { return array(nodes_of(m).cases); }},
    {"EDGV", Part::kOctree, true, [](LodModel& m, Records&) { return array(nodes_of(m).edge_vertices); }, 2, kUnpacked},
    {"EDGM", Part::kOctree, true, [](LodModel&, Records& r) { return array(r.packed.edge_masks); }, kPacked},
    {"EDGP", Part::kOctree, true, [](LodModel&, Records& r) { return array(r.packed.edge_vertices); }, kPacked},
    {"FTRI", Part::kOctree, true, [](LodModel& m, Records&) { return array(nodes_of(m).first_triangle); }, 2, kUnpacked},
    {"NTRI", Part::kOctree, true, [](LodModel& m, Records&) { return array(nodes_of(m).triangle_counts); }, 2, kUnpacked},
    {"TMSK", Part::kOctree, true, [](LodModel&, Records& r) { return array(r.packed.triangle_masks); }, kPacked},
    {"METR", Part::kOctree, true, [](LodModel& m, Records&) { return array(nodes_of(m).metrics); }},
    {"BINS", Part::kOctree, true, [](LodModel& m, Records&) { return array(transitions_of(m).boundary_inside); }},
    {"SUBV", Part::kOctree, true, [](LodModel& m, Records&) { return array(transitions_of(m).sub_edge_vertices); }, 2, kUnpacked},
    {"SUBM", Part::kOctree, true, [](LodModel&, Records& r) { return array(r.packed.sub_edge_masks); }, kPacked},
    {"SUBP", Part::kOctree, true, [](LodModel&, Records& r) { return array(r.packed.sub_edge_vertices); }, kPacked},
    {"CNTR", Part::kOctree, true, [](LodModel& m, Records&) { return array(transitions_of(m).centre_vertices); }},
    {"NBRS", Part::kOctree, true, [](LodModel& m, Records&) { return array(transitions_of(m).neighbours); }, 2, kUnpacked},
    {"TRIS", Part::kOctree, true, [](LodModel& m, Records&) { return array(m.octree->tree.triangles); }, 2, kUnpacked},
    {"PTRI", Part::kOctree, true, [](LodModel& m, Records&) { return array(patches_of(m).triangles); }},
    {"PGRP", Part::kOctree, true, [](LodModel& m, Records&) { return array(patches_of(m).group_first); }},
    {"PNDF", Part::kOctree, true, [](LodModel& m, Records&) { return array(patches_of(m).needs_first); }},
    {"PNDS", Part::kOctree, true, [](LodModel& m, Records&) { return array(patches_of(m).needs); }},
    {"LODO", Part::kOctree, true, [](LodModel& m, Records&) { return array(m.octree->lod.order); }},
    {"LODA", Part::kOctree, true, [](LodModel& m, Records&) { return array(m.octree->lod.accumulated); }},
    // 1.1, optional: older readers offer levels inside it.
    {"PINC", Part::kOctree, false, [](LodModel&, Records& r) { return record(&r.pinned, 8); }},
    // 4.1, optional: older readers offer levels inside the coarsening's steps.
    {"STEP", Part::kOctree, false, [](LodModel& m, Records&) { return array(m.octree->lod.inside_steps); }},
    // 4.2, optional: older files were counted without it (all zero).
    {"STRF", Part::kOctree, false, [](LodModel& m, Records&) { return array(transitions_of(m).straight_faces); }},
    // 4.3, optional: older readers cut the internal nodes' polygons as the case table does.
    {"OWNC", Part::kOctree, false, [](LodModel&, Records& r) { return array(r.packed.own_cuts); }, kPacked},
    {"CINF", Part::kClusters, true, [](LodModel&, Records& r) { return record(r.cluster_info, 24); }, 3},
    {"CLUS", Part::kClusters, true, [](LodModel& m, Records&) { return array(m.clusters->clusters); }, 3},
    {"CTRI", Part::kClusters, true, [](LodModel& m, Records&) { return array(m.clusters->triangles); }, 3},
    {"CGRP", Part::kClusters, true, [](LodModel& m, Records&) { return array(m.clusters->groups); }, 3},
    // 4.4, optional: older readers read the clusters whole; this one derives the pages.
    {"PAGE", Part::kClusters, false, [](LodModel& m, Records&) { return array(m.clusters->pages); }, kPacked},
    // 4.6, optional: older readers, and load_model, read the clusters whole;
    // a paged reader (lod/clusters/paged_model.h) reads a page's geometry at a time.
    {"PGIX", Part::kClusters, false, [](LodModel&, Records& r) { return array(r.page_extents); }, kPacked},
    {"PGEO", Part::kClusters, false, [](LodModel&, Records& r) { return streamed(r.page_bytes); }, kPacked},
};

bool has_part(const LodModel& model, Part part) {
  return part == Part::kVertices || (part == Part::kOctree ? model.octree.has_value() : model.clusters.has_value());
}

// The records as the writer of format `major` lays them out.
Records records_of(const LodModel& model, std::uint32_t major) {
  Records r;
  for (int i = 0; i < 3; ++i) r.origin[i] = model.origin[i];
  if (model.octree && major >= kPacked) r.packed = pack_octree(model.octree->tree);
  if (model.octree) {
    const McOctree& t = model.octree->tree;
    for (int i = 0; i < 3; ++i) std::memcpy(r.grid + 8 * i, &t.grid.origin[i], 8);
    std::memcpy(r.grid + 24, &t.grid.cube_size, 8);
    const std::int32_t resolution = t.grid.resolution, depth = t.depth;
    std::memcpy(r.grid + 32, &resolution, 4);
    std::memcpy(r.grid + 36, &depth, 4);
    put_u64(r.grid + 40, std::uint64_t(t.mesh_vertices));
    r.pinned = model.octree->lod.pinned;
  }
  if (model.clusters) {
    r.cluster_info[0] = std::uint64_t(model.clusters->full_triangles);
    r.cluster_info[1] = model.cluster_vertex_first;
    r.cluster_info[2] = model.cluster_vertex_count;
  }
  return r;
}

// One section as the writer lays it out.
using Emit = std::function<void(const std::uint8_t*, std::size_t)>;

struct OutSection {
  std::uint32_t tag;
  std::uint32_t element_size;
  std::uint64_t count;
  const void* data;
  std::uint32_t flags = kRequired;
  // The payload when it is not in memory (a spool, or pages encoded as they
  // are written), with its checksum taken beforehand.
  std::function<void(const Emit&)> stream;
  std::uint64_t stream_checksum = 0;
};

// One directory entry as read.
struct Section {
  std::uint32_t tag, flags, element_size;
  std::uint64_t count, offset, length, checksum;
};

std::uint64_t padded(std::uint64_t n) { return (n + 7) & ~std::uint64_t(7); }

}  // namespace

std::uint64_t model_checksum(const void* data, std::size_t size, std::uint64_t seed) {
  return XXH64(data, size, seed);
}

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

// The file's bytes in order, to `out` (called with runs of bytes), with the
// trailer's checksum taken as they pass: a model is written without a copy
// of it in memory.
void emit_model(const LodModel& model, std::uint32_t major,
                const std::function<void(const std::uint8_t*, std::size_t)>& out) {
  if (major < kUnpacked || major > kModelFormatMajor)
    throw std::invalid_argument("encode_model: format " + std::to_string(major) + " is not written");
  Records records = records_of(model, major);
  // Pages of geometry: encoded once here for their sizes and checksums, and
  // again as they are written, so that they are never held whole.
  bool paged = model.clusters && major >= kPacked && !model.clusters->pages.empty() &&
               pages_follow_triangles(*model.clusters);
  std::uint64_t pages_checksum = 0;
  if (paged) {
    const ClusterHierarchy& h = *model.clusters;
    std::unique_ptr<XXH64_state_t, XXH_errorcode (*)(XXH64_state_t*)> hash(XXH64_createState(), XXH64_freeState);
    if (!hash) throw std::bad_alloc();
    XXH64_reset(hash.get(), 0);
    records.page_extents.resize(h.pages.size());
    paged = encode_pages(h, model.vertices, [&](const EncodedPage& page) {
      PageExtent& e = records.page_extents[page.page];
      e = {records.page_bytes, std::uint32_t(page.blob.size()), 0, page.checksum, {}, {}};
      std::memcpy(&e.vertices, page.blob.data(), 4);
      for (int k = 0; k < 3; ++k) e.min[k] = page.box.min[k], e.max[k] = page.box.max[k];
      XXH64_update(hash.get(), page.blob.data(), page.blob.size());
      records.page_bytes += page.blob.size();
    });
    pages_checksum = XXH64_digest(hash.get());
    if (!paged) records.page_extents.clear(), records.page_bytes = 0;
  }
  // The table's payloads are only read here.
  LodModel& readable = const_cast<LodModel&>(model);
  std::vector<OutSection> sections;
  for (const SectionSpec& spec : kSections) {
    if (!has_part(model, spec.part) || !spec.in(major)) continue;
    // A hierarchy made by hand, without pages: the reader derives them.
    if (std::strcmp(spec.tag, "PAGE") == 0 && model.clusters->pages.empty()) continue;
    if ((std::strcmp(spec.tag, "PGIX") == 0 || std::strcmp(spec.tag, "PGEO") == 0) && !paged) continue;
    // A model in its inputs' own frame: files stay as they were.
    if (std::strcmp(spec.tag, "ORGN") == 0 && model.origin == Vec3d::Zero()) continue;
    const Payload p = spec.payload(readable, records);
    sections.push_back({fourcc(spec.tag), p.element_size, p.count, p.data, spec.required ? kRequired : 0, {}, 0});
    OutSection& out = sections.back();
    // A hierarchy built in blocks may hold its triangles on disk.
    if (out.tag == fourcc("CTRI") && model.clusters->spool) {
      const TriangleSpool* spool = model.clusters->spool.get();
      out.count = spool->size();
      out.stream = [spool](const Emit& emit) { spool->read(emit); };
      out.stream_checksum = spool->checksum();
    }
    if (out.tag == fourcc("PGEO")) {
      out.stream = [&](const Emit& emit) {
        encode_pages(*model.clusters, model.vertices,
                     [&](const EncodedPage& page) { emit(page.blob.data(), page.blob.size()); });
      };
      out.stream_checksum = pages_checksum;
    }
  }
  const std::size_t count = sections.size();
  const std::uint64_t directory_end = kHeaderBytes + kEntryBytes * count + 8;
  std::uint64_t length = directory_end;
  for (const OutSection& s : sections) length = padded(length + s.element_size * s.count);
  length += 8;

  std::vector<std::uint8_t> head(directory_end, 0);
  std::uint8_t* header = head.data();
  std::memcpy(header, kMagic, 8);
  put_u32(header + 8, major);
  put_u32(header + 12, major == kModelFormatMajor ? kModelFormatMinor : 0);
  put_u32(header + 16, std::uint32_t(count));
  put_u32(header + 20, 0);
  put_u64(header + 24, length);
  put_u64(header + 32, model_checksum(header, 32));
  std::uint64_t offset = directory_end;
  for (std::size_t i = 0; i < count; ++i) {
    const OutSection& s = sections[i];
    const std::uint64_t size = s.element_size * s.count;
    std::uint8_t* e = head.data() + kHeaderBytes + kEntryBytes * i;
    put_u32(e, s.tag);
    put_u32(e + 4, s.flags);
    put_u32(e + 8, s.element_size);
    put_u32(e + 12, 0);
    put_u64(e + 16, s.count);
    put_u64(e + 24, offset);
    put_u64(e + 32, size);
    put_u64(e + 40, s.stream ? s.stream_checksum : model_checksum(s.data, size));
    offset = padded(offset + size);
  }
  put_u64(head.data() + directory_end - 8, model_checksum(head.data() + kHeaderBytes, kEntryBytes * count));

  std::unique_ptr<XXH64_state_t, XXH_errorcode (*)(XXH64_state_t*)> file(XXH64_createState(), XXH64_freeState);
  if (!file) throw std::bad_alloc();
  XXH64_reset(file.get(), 0);
  auto emit = [&](const std::uint8_t* bytes, std::size_t size) {
    if (size == 0) return;
    XXH64_update(file.get(), bytes, size);
    out(bytes, size);
  };
  emit(head.data(), head.size());
  static const std::uint8_t zeros[8] = {};
  offset = directory_end;
  for (const OutSection& s : sections) {
    const std::uint64_t size = s.element_size * s.count;
    if (s.stream) s.stream(emit);
    else emit(static_cast<const std::uint8_t*>(s.data), size);
    emit(zeros, padded(offset + size) - (offset + size));
    offset = padded(offset + size);
  }
  std::uint8_t trailer[8];
  put_u64(trailer, XXH64_digest(file.get()));
  out(trailer, 8);
}

}  // namespace

std::vector<std::uint8_t> encode_model(const LodModel& model, std::uint32_t major) {
  std::vector<std::uint8_t> bytes;
  emit_model(model, major, [&](const std::uint8_t* p, std::size_t n) { bytes.insert(bytes.end(), p, p + n); });
  return bytes;
}

void check_model_output(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext != ".mco") throw InputError(path, "a model file needs the extension .mco, got '" + ext + "'");
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  std::error_code ec;
  if (!folder.empty() && !std::filesystem::is_directory(folder, ec))
    throw InputError(path, "cannot write: folder " + folder.string() + " does not exist");
}

void save_model(const std::string& path, const LodModel& model) {
  check_model_output(path);
  write_atomically(path, [&](const std::string& tmp) {
    FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw InputError(path, std::string("cannot write: ") + std::strerror(errno));
    bool written = true;
    int error = 0;
    try {
      emit_model(model, kModelFormatMajor, [&](const std::uint8_t* p, std::size_t n) {
        if (written && std::fwrite(p, 1, n, f) != n) written = false, error = errno;
      });
    } catch (...) {
      std::fclose(f);
      throw;
    }
    if (std::fclose(f) != 0 || !written)
      throw InputError(path, std::string("cannot write: ") + std::strerror(written ? errno : error));
  });
}

namespace {

// `path` opened for reading, and its size; InputError when it is missing,
// not a regular file, or unreadable.
int open_model_file(const std::string& path, std::uintmax_t* size) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, "cannot read the model: no such file");
  if (!fs::is_regular_file(path, ec)) throw InputError(path, "cannot read the model: not a regular file");
  *size = fs::file_size(path, ec);
  if (ec) throw InputError(path, "cannot read the model: " + ec.message());
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) throw InputError(path, std::string("cannot read the model: ") + std::strerror(errno));
  return fd;
}

}  // namespace

LodModel load_model(const std::string& path) {
  std::uintmax_t size = 0;
  const int fd = open_model_file(path, &size);
  // Mapped rather than read into a buffer: the decoder copies each section
  // once, straight from the page cache.
  void* mapped = size ? ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0) : MAP_FAILED;
  if (mapped != MAP_FAILED) {
    ::close(fd);
    const std::unique_ptr<void, std::function<void(void*)>> unmap(mapped, [size](void* p) { ::munmap(p, size); });
    return decode_model(static_cast<const std::uint8_t*>(mapped), size, path);
  }
  // Not mappable (or empty): read it whole. Not zeroed first: every byte is read over.
  const std::unique_ptr<std::uint8_t[]> bytes(new std::uint8_t[std::max<std::uintmax_t>(size, 1)]);
  std::size_t got = 0;
  while (got < size) {
    const ssize_t r = ::read(fd, bytes.get() + got, size - got);
    if (r <= 0) break;
    got += std::size_t(r);
  }
  ::close(fd);
  if (got != size)
    throw InputError(path, "cannot read the model: read " + std::to_string(got) + " of " + std::to_string(size) + " bytes");
  return decode_model(bytes.get(), size, path);
}

namespace {

constexpr std::size_t kMaxIndex = std::size_t(std::numeric_limits<std::int32_t>::max());

std::string bytes_text(std::uint64_t n) { return std::to_string(n) + (n == 1 ? " byte" : " bytes"); }

// Reads one model from bytes, phase by phase: the header, the directory, the
// checksums, the sections (walking kSections), then whether the contents
// agree, so that extraction cannot read out of bounds on what it returns.
class Decoder {
 public:
  Decoder(const std::uint8_t* data, std::size_t size, const std::string& source)
      : data_(data), size_(size), source_(source) {}
  // Paged: reads from `fd` (a file of `size` bytes) only the header, the
  // directory and the sections it decodes, checking each one's checksum.
  Decoder(int fd, std::size_t size, const std::string& source) : data_(nullptr), size_(size), source_(source), fd_(fd) {}

  LodModel decode();
  ModelPagesHead decode_pages_head();

 private:
  [[noreturn]] void fail(const std::string& what) const { throw InputError(source_, what); }
  [[noreturn]] void bad(const std::string& what) const { fail("inconsistent model: " + what); }

  void read_header();
  void read_directory();
  void verify_length_and_checksums() const;
  void index_sections();
  const Section& section(const char* tag) const;
  void read_part(Part part, LodModel* model);
  void read_grid(McOctree* t);
  void read_pinned(LodArray* lod);
  void read_origin(LodModel* model);
  void check_vertices(const LodModel& model) const;
  void decode_clusters(LodModel* model);
  void check_pages(ClusterHierarchy& h) const;
  void check_page_extents(const ClusterHierarchy& h, const std::vector<PageExtent>& extents) const;
  const std::uint8_t* payload(const Section& s);
  void read_head();
  void check_octree_arrays(const McOctree& t) const;
  std::size_t check_nodes(const McOctree& t) const;
  void check_transitions(const McOctree& t, std::size_t internal) const;
  void check_lod_array(const McOctree& t, const LodArray& lod, std::size_t internal) const;

  const std::uint8_t* data_;
  std::size_t size_;
  const std::string& source_;
  int fd_ = -1;                                  // paged: the file, read a section at a time
  std::vector<std::uint8_t> head_;               // paged: the header and directory
  std::vector<std::vector<std::uint8_t>> held_;  // paged: the sections read
  std::uint64_t bytes_read_ = 0;                 // paged
  std::uint32_t major_ = 0, minor_ = 0;
  std::string format_;
  std::uint64_t file_length_ = 0, directory_end_ = 0;
  std::vector<Section> sections_;
  std::map<std::uint32_t, const Section*> by_tag_;
  Records records_;
  std::size_t vertices_ = 0;
};

// Header: what the file is, before anything is trusted.
void Decoder::read_header() {
  if (size_ == 0) fail("not a scan2lod model (.mco): the file is empty");
  if (std::memcmp(data_, kMagic, std::min<std::size_t>(size_, 8)) != 0)
    fail("not a scan2lod model (.mco): bad magic, the file does not start with \"SCAN2LOD\"");
  if (size_ < kHeaderBytes) fail("truncated in the header: " + bytes_text(size_) + " of " + std::to_string(kHeaderBytes));
  if (model_checksum(data_, 32) != get_u64(data_ + 32)) fail("checksum mismatch in the header (damaged file)");
  major_ = get_u32(data_ + 8);
  minor_ = get_u32(data_ + 12);
  if (major_ > kModelFormatMajor)
    fail("written by a newer scan2lod (format " + std::to_string(major_) + "." + std::to_string(minor_) +
         ", this reads up to " + std::to_string(kModelFormatMajor) + ")");
  if (major_ == 0) fail("format version 0 was never written by scan2lod");
  if (major_ < 2)
    fail("written by an older scan2lod (format " + std::to_string(major_) + "." + std::to_string(minor_) +
         "), whose crack patching triangulated differently from this one's; rebuild the model with scan2lod build");
  format_ = "format " + std::to_string(major_) + "." + std::to_string(minor_);
  const std::uint64_t section_count = get_u32(data_ + 16);
  file_length_ = get_u64(data_ + 24);
  directory_end_ = kHeaderBytes + kEntryBytes * section_count + 8;
  if (file_length_ < directory_end_ + 8)
    fail("the header's file length " + std::to_string(file_length_) + " cannot hold " +
         std::to_string(section_count) + " sections");
}

// Directory: where each section lies; all of it inside the stated length.
void Decoder::read_directory() {
  const std::uint64_t section_count = get_u32(data_ + 16);
  if (size_ < directory_end_)
    fail("truncated in the section directory: " + bytes_text(size_) + " of " + std::to_string(file_length_));
  if (model_checksum(data_ + kHeaderBytes, kEntryBytes * section_count) != get_u64(data_ + directory_end_ - 8))
    fail("checksum mismatch in the section directory (damaged file)");
  sections_.resize(section_count);
  for (std::size_t i = 0; i < section_count; ++i) {
    const std::uint8_t* e = data_ + kHeaderBytes + kEntryBytes * i;
    Section& s = sections_[i];
    s = {get_u32(e), get_u32(e + 4), get_u32(e + 8), get_u64(e + 16), get_u64(e + 24), get_u64(e + 32), get_u64(e + 40)};
    const std::string name = "section " + tag_name(s.tag);
    if (s.element_size == 0 || s.count > std::numeric_limits<std::uint64_t>::max() / s.element_size ||
        s.count * s.element_size != s.length)
      fail(name + ": " + std::to_string(s.count) + " elements of " + bytes_text(s.element_size) + " do not make its " +
           bytes_text(s.length));
    if (s.offset < directory_end_ || s.offset > file_length_ - 8 || s.length > file_length_ - 8 - s.offset)
      fail(name + ": its " + bytes_text(s.length) + " at offset " + std::to_string(s.offset) +
           " lie outside the model's " + bytes_text(file_length_));
  }
}

// Length: a short file is truncated somewhere; say where. Then every checksum.
void Decoder::verify_length_and_checksums() const {
  if (size_ < file_length_) {
    const Section* cut = nullptr;
    for (const Section& s : sections_)
      if (s.offset + s.length > size_ && (!cut || s.offset < cut->offset)) cut = &s;
    fail("truncated in " + (cut ? "section " + tag_name(cut->tag) : std::string("the trailing checksum")) + ": " +
         bytes_text(size_) + " of " + std::to_string(file_length_));
  }
  if (size_ > file_length_)
    fail(bytes_text(size_ - file_length_) + " after the end of the model (" + bytes_text(file_length_) + ")");
  if (fd_ >= 0) return;  // paged: each section is checked as it is read
  for (const Section& s : sections_)
    if (model_checksum(data_ + s.offset, s.length) != s.checksum)
      fail("checksum mismatch in section " + tag_name(s.tag) + " (damaged file)");
  if (model_checksum(data_, file_length_ - 8) != get_u64(data_ + file_length_ - 8))
    fail("checksum mismatch over the whole file (damaged padding)");
}

// Sections by tag: each known one once; unknown ones only if optional.
void Decoder::index_sections() {
  for (const Section& s : sections_)
    if (!by_tag_.emplace(s.tag, &s).second) fail("section " + tag_name(s.tag) + " appears twice");
  for (const Section& s : sections_) {
    const bool known = std::any_of(std::begin(kSections), std::end(kSections),
                                   [&](const SectionSpec& spec) { return fourcc(spec.tag) == s.tag; });
    if ((s.flags & kRequired) && !known)
      fail("needs section " + tag_name(s.tag) + ", which this scan2lod does not know (" + format_ + ", this reads " +
           std::to_string(kModelFormatMajor) + "." + std::to_string(kModelFormatMinor) + "): written by a newer scan2lod");
  }
}

const Section& Decoder::section(const char* tag) const {
  std::uint32_t code = 0;
  for (int i = 0; i < 4; ++i) code |= std::uint32_t(std::uint8_t(tag[i])) << (8 * i);
  auto it = by_tag_.find(code);
  if (it == by_tag_.end()) throw InputError(source_, "missing section '" + std::string(tag) + "'");
  return *it->second;
}

// The arrays of one part, as kSections lists them (records are read by their
// own functions, which check their sizes).
void Decoder::read_part(Part part, LodModel* model) {
  for (const SectionSpec& spec : kSections) {
    if (spec.part != part || !spec.in(major_)) continue;
    const Payload p = spec.payload(*model, records_);
    if (!p.resize || (!spec.required && !by_tag_.count(fourcc(spec.tag)))) continue;
    const Section& s = section(spec.tag);
    if (s.element_size != p.element_size)
      fail("section '" + std::string(spec.tag) + "' has elements of " + bytes_text(s.element_size) + ", expected " +
           std::to_string(p.element_size));
    // Paged: the triangles stay in the file, read page by page from 'PGEO'.
    if (fd_ >= 0 && s.tag == fourcc("CTRI")) continue;
    void* into = p.resize(p.vector, s.count);  // s.length bytes, inside the file: bounded by its size
    if (s.length) std::memcpy(into, payload(s), s.length);
  }
}

void Decoder::read_grid(McOctree* t) {
  const Section& s = section("GRID");
  if (s.count != 1 || s.element_size < kGridRecordBytes)
    fail("section 'GRID' must be one record of at least " + std::to_string(kGridRecordBytes) + " bytes");
  const std::uint8_t* g = payload(s);
  for (int i = 0; i < 3; ++i) std::memcpy(&t->grid.origin[i], g + 8 * i, 8);
  std::memcpy(&t->grid.cube_size, g + 24, 8);
  std::int32_t resolution, depth;
  std::memcpy(&resolution, g + 32, 4);
  std::memcpy(&depth, g + 36, 4);
  t->grid.resolution = resolution;
  t->depth = depth;
  t->mesh_vertices = std::size_t(get_u64(g + 40));
}

// Optional (added in 1.1): without it nothing is pinned.
void Decoder::read_pinned(LodArray* lod) {
  if (!by_tag_.count(fourcc("PINC"))) return;
  const Section& s = section("PINC");
  if (s.element_size != 8)
    fail("section 'PINC' has elements of " + bytes_text(s.element_size) + ", expected 8");
  if (s.count != 1) fail("section 'PINC' must hold one count, not " + std::to_string(s.count));
  lod->pinned = std::size_t(std::min<std::uint64_t>(get_u64(payload(s)), std::numeric_limits<std::size_t>::max()));
}

// Optional (added in 4.5): without it the vertices are in the inputs' frame.
void Decoder::read_origin(LodModel* model) {
  if (!by_tag_.count(fourcc("ORGN"))) return;
  const Section& s = section("ORGN");
  if (s.count != 1 || s.element_size != 24) bad("section 'ORGN' must be one record of 24 bytes");
  const std::uint8_t* origin = payload(s);
  for (int i = 0; i < 3; ++i) std::memcpy(&model->origin[i], origin + 8 * i, 8);
  if (!model->origin.allFinite()) bad("section 'ORGN': the origin must be a finite point");
}

void Decoder::check_vertices(const LodModel& model) const {
  const std::size_t vertices = model.vertices.size();
  if (vertices > kMaxIndex) bad(std::to_string(vertices) + " vertices, more than 32-bit indices address");
  if (!model.vertices.normals.empty() && model.vertices.normals.size() != vertices)
    bad(std::to_string(model.vertices.normals.size()) + " normals for " + std::to_string(vertices) + " vertices");
  if (!model.vertices.colors.empty() && model.vertices.colors.size() != vertices)
    bad(std::to_string(model.vertices.colors.size()) + " colours for " + std::to_string(vertices) + " vertices");
}

// The cluster hierarchy's sections, checked so that no cut can read out of
// bounds: ranges inside their arrays, groups that exist, finite bounds.
void Decoder::decode_clusters(LodModel* model) {
  const Section& info = section("CINF");
  if (info.count != 1 || info.element_size != 24) bad("section 'CINF' must be one record of 24 bytes");
  const std::uint8_t* record = payload(info);
  const std::uint64_t full = get_u64(record), first = get_u64(record + 8), count = get_u64(record + 16);
  const std::size_t vertices = vertices_;
  if (first > vertices || count > vertices - first)
    bad("the cluster hierarchy's vertices " + std::to_string(first) + "+" + std::to_string(count) + " lie outside the " +
        std::to_string(vertices) + " vertices");
  model->clusters.emplace();
  read_part(Part::kClusters, model);
  ClusterHierarchy& h = *model->clusters;
  const std::uint64_t stored = fd_ >= 0 ? section("CTRI").count : h.triangles.size();
  h.full_triangles = std::int64_t(std::min<std::uint64_t>(full, std::uint64_t(std::numeric_limits<std::int64_t>::max())));
  if (h.clusters.empty()) bad("the cluster hierarchy has no clusters");
  for (std::size_t i = 0; i < h.triangles.size(); ++i)
    for (std::int32_t v : h.triangles[i])
      if (v < std::int64_t(first) || std::uint64_t(v) >= first + count)
        bad("section 'CTRI': triangle " + std::to_string(i) + " names vertex " + std::to_string(v) + " outside " +
            std::to_string(first) + "+" + std::to_string(count));
  for (std::size_t g = 0; g < h.groups.size(); ++g) {
    const GroupBound& b = h.groups[g];
    if (!(std::isfinite(b.center[0]) && std::isfinite(b.center[1]) && std::isfinite(b.center[2]) &&
          std::isfinite(b.radius) && b.radius >= 0 && std::isfinite(b.error) && b.error > 0))
      bad("section 'CGRP': group " + std::to_string(g) + " needs a finite centre, radius >= 0 and error > 0");
  }
  const std::int64_t groups = std::int64_t(h.groups.size());
  std::int64_t level0 = 0;
  for (std::size_t c = 0; c < h.clusters.size(); ++c) {
    const Cluster& cl = h.clusters[c];
    auto where = [c] { return "section 'CLUS': cluster " + std::to_string(c) + ": "; };
    if (cl.triangle_count == 0) bad(where() + "no triangles");
    if (std::uint64_t(cl.first_triangle) + cl.triangle_count > stored)
      bad(where() + "triangles " + std::to_string(cl.first_triangle) + "+" + std::to_string(cl.triangle_count) +
          " past the " + std::to_string(stored) + " of 'CTRI'");
    if (cl.own_group < -1 || cl.own_group >= groups || cl.parent_group < -1 || cl.parent_group >= groups)
      bad(where() + "group " + std::to_string(cl.own_group) + " or " + std::to_string(cl.parent_group) + " of " +
          std::to_string(groups));
    if (cl.own_group >= 0 && cl.own_group == cl.parent_group) bad(where() + "its own group is its parent");
    if ((cl.own_group < 0) != (cl.level == 0)) bad(where() + "level 0 and full detail (no own group) must agree");
    if (cl.own_group >= 0 && cl.parent_group >= 0 &&
        h.groups[std::size_t(cl.parent_group)].error < h.groups[std::size_t(cl.own_group)].error)
      bad(where() + "its parent group's error is below its own");
    if (cl.own_group < 0) level0 += cl.triangle_count;
  }
  if (level0 != h.full_triangles)
    bad("the full-detail clusters hold " + std::to_string(level0) + " triangles, 'CINF' says " +
        std::to_string(h.full_triangles));
  check_pages(h);
  model->cluster_vertex_first = std::size_t(first);
  model->cluster_vertex_count = std::size_t(count);
}

// Pages (4.4) must list the clusters in order, each page's triangles one run,
// and each page's error interval must hold its clusters' own and parent
// errors, so that a viewer that skips pages outside a threshold skips no
// cluster a cut draws. A file without them gets them derived.
void Decoder::check_pages(ClusterHierarchy& h) const {
  if (h.pages.empty()) {
    h.pages = cluster_pages(h);
    return;
  }
  std::size_t next = 0;
  for (std::size_t i = 0; i < h.pages.size(); ++i) {
    const ClusterPage& p = h.pages[i];
    auto where = [i] { return "section 'PAGE': page " + std::to_string(i) + ": "; };
    if (p.first_cluster != next || p.cluster_count == 0 || p.cluster_count > h.clusters.size() - next)
      bad(where() + "clusters " + std::to_string(p.first_cluster) + "+" + std::to_string(p.cluster_count) +
          " do not follow on from cluster " + std::to_string(next) + " of " + std::to_string(h.clusters.size()));
    if (!(std::isfinite(p.center[0]) && std::isfinite(p.center[1]) && std::isfinite(p.center[2]) && p.radius >= 0 &&
          p.min_error >= 0 && p.min_error <= p.max_error))
      bad(where() + "needs a finite centre, radius >= 0 and 0 <= min error <= max error");
    for (std::size_t c = p.first_cluster; c < std::size_t(p.first_cluster) + p.cluster_count; ++c) {
      const Cluster& cl = h.clusters[c];
      if (c > p.first_cluster &&
          h.clusters[c - 1].first_triangle + h.clusters[c - 1].triangle_count != cl.first_triangle)
        bad(where() + "cluster " + std::to_string(c) + "'s triangles do not follow on from the one before");
      const float own = cl.own_group < 0 ? 0.f : h.groups[std::size_t(cl.own_group)].error;
      const float parent = cl.parent_group < 0 ? std::numeric_limits<float>::infinity()
                                               : h.groups[std::size_t(cl.parent_group)].error;
      if (own < p.min_error || parent > p.max_error)
        bad(where() + "cluster " + std::to_string(c) + "'s errors lie outside the page's");
    }
    next += p.cluster_count;
  }
  if (next != h.clusters.size())
    bad("section 'PAGE': the pages hold " + std::to_string(next) + " of the " + std::to_string(h.clusters.size()) +
        " clusters");
}

void Decoder::check_octree_arrays(const McOctree& t) const {
  // Contents: everything extraction indexes must be in range, and the tree a
  // tree, so that a crafted file cannot make it read out of bounds.
  const std::size_t n = t.nodes.keys.size(), vertices = vertices_;
  if (n == 0) bad("the octree has no nodes");
  if (n > kMaxIndex) bad(std::to_string(n) + " nodes, more than 32-bit indices address");
  auto per_node = [&](const char* tag, std::size_t count) {
    if (count != n)
      bad("section '" + std::string(tag) + "' has " + std::to_string(count) + " entries for the " + std::to_string(n) +
          " nodes of 'KEYS'");
  };
  per_node("LEVL", t.nodes.levels.size());
  per_node("PRNT", t.nodes.parents.size());
  per_node("FCHD", t.nodes.first_child.size());
  per_node("NCHD", t.nodes.child_counts.size());
  per_node("CASE", t.nodes.cases.size());
  per_node("EDGV", t.nodes.edge_vertices.size());
  per_node("FTRI", t.nodes.first_triangle.size());
  per_node("NTRI", t.nodes.triangle_counts.size());
  per_node("METR", t.nodes.metrics.size());
  if (t.depth < 0 || t.depth > 19 || t.grid.resolution != (1 << t.depth))
    bad("resolution " + std::to_string(t.grid.resolution) + " is not 2^depth for depth " + std::to_string(t.depth));
  if (!t.grid.origin.allFinite() || !std::isfinite(t.grid.cube_size) || !(t.grid.cube_size > 0))
    bad("the grid's origin and cube size must be finite, the cube size positive");
  if (t.mesh_vertices > vertices)
    bad("mesh_vertices " + std::to_string(t.mesh_vertices) + " exceeds the " + std::to_string(vertices) + " vertices");
  if (t.triangles.size() > kMaxIndex) bad("more triangles than 32-bit indices address");
  auto check_triangles = [&](const char* tag, const auto& tris) {
    for (std::size_t i = 0; i < tris.size(); ++i)
      for (std::int32_t v : tris[i])
        if (v < 0 || std::size_t(v) >= vertices)
          bad("section '" + std::string(tag) + "': triangle " + std::to_string(i) + " names vertex " +
              std::to_string(v) + " of " + std::to_string(vertices));
  };
  check_triangles("TRIS", t.triangles);
  check_triangles("PTRI", t.patches.triangles);

  // Hole patches by group: offsets that run from 0 to the end of their array.
  auto check_offsets = [&](const char* tag, const auto& first, std::size_t total,
                           const char* of) {
    if (first.empty() ? total != 0 : first.front() != 0 || std::size_t(first.back()) != total ||
                                         !std::is_sorted(first.begin(), first.end()))
      bad("section '" + std::string(tag) + "' does not run from 0 to the " + std::to_string(total) + " entries of '" +
          of + "' in order");
  };
  if (t.patches.group_first.empty() && !t.patches.triangles.empty())
    bad("patch triangles without groups ('PGRP' is empty)");
  check_offsets("PGRP", t.patches.group_first, t.patches.triangles.size(), "PTRI");
  if (t.patches.needs_first.size() != t.patches.group_first.size())
    bad("section 'PNDF' has " + std::to_string(t.patches.needs_first.size()) + " entries, 'PGRP' " +
        std::to_string(t.patches.group_first.size()));
  check_offsets("PNDF", t.patches.needs_first, t.patches.needs.size(), "PNDS");
  for (std::int32_t v : t.patches.needs)
    if (v < 0 || std::size_t(v) >= n) bad("section 'PNDS' names node " + std::to_string(v) + " of " + std::to_string(n));

}

// The tree a tree, every index in range.
std::size_t Decoder::check_nodes(const McOctree& t) const {
  const std::size_t n = t.nodes.keys.size(), vertices = vertices_;
  if (t.nodes.parents[0] != -1 || t.nodes.levels[0] != 0 || t.nodes.keys[0] != 0) bad("node 0 is not the root");
  std::size_t internal = 0;
  for (std::size_t i = 0; i < n; ++i) {
    auto node = [i] { return "node " + std::to_string(i) + ": "; };  // built only on failure
    const int level = t.nodes.levels[i];
    if (level > t.depth) bad(node() + "level " + std::to_string(level) + " below the leaves' " + std::to_string(t.depth));
    if (t.nodes.keys[i] >> 60) bad(node() + "key out of range");
    int x, y, z;
    unpack_key(t.nodes.keys[i], &x, &y, &z);
    if (std::max({x, y, z}) >= (1 << level)) bad(node() + "key outside its level's lattice");
    if (i > 0) {
      const std::int32_t p = t.nodes.parents[i];
      if (p < 0 || std::size_t(p) >= n) bad(node() + "parent " + std::to_string(p) + " of " + std::to_string(n) + " nodes");
      if (t.nodes.first_child[p] < 0 || std::size_t(t.nodes.first_child[p]) > i ||
          i >= std::size_t(t.nodes.first_child[p]) + t.nodes.child_counts[p])
        bad(node() + "not among its parent " + std::to_string(p) + "'s children");
    }
    if (t.nodes.first_child[i] < 0) {
      if (t.nodes.child_counts[i] != 0 || level != t.depth) bad(node() + "a leaf must sit at the depth with no children");
    } else {
      ++internal;
      const std::size_t first = std::size_t(t.nodes.first_child[i]);
      if (t.nodes.child_counts[i] < 1 || t.nodes.child_counts[i] > 8 || first + t.nodes.child_counts[i] > n)
        bad(node() + "children " + std::to_string(first) + "+" + std::to_string(t.nodes.child_counts[i]) +
            " are not 1 to 8 of the " + std::to_string(n) + " nodes");
      for (std::size_t c = first; c < first + t.nodes.child_counts[i]; ++c) {
        int cx, cy, cz;
        unpack_key(t.nodes.keys[c], &cx, &cy, &cz);
        if (t.nodes.parents[c] != std::int32_t(i) || t.nodes.levels[c] != level + 1 || cx >> 1 != x || cy >> 1 != y ||
            cz >> 1 != z)
          bad(node() + "child " + std::to_string(c) + " does not lie inside it on the next level");
      }
    }
    if (t.nodes.first_triangle[i] < 0 ||
        std::size_t(t.nodes.first_triangle[i]) + t.nodes.triangle_counts[i] > t.triangles.size())
      bad(node() + "triangles " + std::to_string(t.nodes.first_triangle[i]) + "+" + std::to_string(t.nodes.triangle_counts[i]) +
          " past the " + std::to_string(t.triangles.size()) + " of 'TRIS'");
    for (std::int32_t v : t.nodes.edge_vertices[i])
      if (v < -1 || (v >= 0 && std::size_t(v) >= vertices))
        bad(node() + "edge vertex " + std::to_string(v) + " of " + std::to_string(vertices));
  }

  return internal;
}

void Decoder::check_transitions(const McOctree& t, std::size_t internal) const {
  const std::size_t n = t.nodes.keys.size(), vertices = vertices_;
  // Crack patching (lod/octree/transition.h): the internal nodes come first, and
  // every crossing the transition triangulation can join has a vertex.
  const std::size_t with_transitions = t.transitions.centre_vertices.size();
  if (with_transitions != internal)
    bad("section 'CNTR' has " + std::to_string(with_transitions) + " entries for the " + std::to_string(internal) +
        " internal nodes");
  auto per_internal = [&](const char* tag, std::size_t count) {
    if (count != internal)
      bad("section '" + std::string(tag) + "' has " + std::to_string(count) + " entries for the " +
          std::to_string(internal) + " internal nodes");
  };
  per_internal("BINS", t.transitions.boundary_inside.size());
  per_internal("SUBV", t.transitions.sub_edge_vertices.size());
  per_internal("NBRS", t.transitions.neighbours.size());
  per_internal("STRF", t.transitions.straight_faces.size());
  const auto& sub_edges = transition_sub_edges();
  auto vertex_ok = [&](std::int32_t v) { return v >= -1 && (v < 0 || std::size_t(v) < vertices); };
  int corner_point[8], edge_ends[12][2];
  for (int c = 0; c < 8; ++c) corner_point[c] = lattice_of_corner(c);
  for (int e = 0; e < 12; ++e)
    for (int end = 0; end < 2; ++end) edge_ends[e][end] = corner_point[edge_corner(e, end)];
  for (std::size_t i = 0; i < internal; ++i) {
    auto node = [i] { return "node " + std::to_string(i) + ": "; };  // built only on failure
    if (t.nodes.first_child[i] < 0) bad(node() + "a leaf among the first " + std::to_string(internal) + " nodes");
    const std::uint32_t inside = t.transitions.boundary_inside[i];
    if (inside >> 27) bad(node() + "boundary signs beyond the 27 lattice points");
    auto in = [&](int p) { return (inside >> p) & 1; };
    bool crossing = false;
    for (int c = 0; c < 8; ++c)
      if (std::uint32_t(in(corner_point[c])) != std::uint32_t((t.nodes.cases[i] >> c) & 1))
        bad(node() + "boundary signs disagree with its case at corner " + std::to_string(c));
    for (int e = 0; e < 12; ++e)
      if (in(edge_ends[e][0]) != in(edge_ends[e][1])) {
        crossing = true;
        if (t.nodes.edge_vertices[i][e] < 0) bad(node() + "edge " + std::to_string(e) + " changes sign without a vertex");
      }
    for (int e = 0; e < kSubEdges; ++e) {
      const std::int32_t v = t.transitions.sub_edge_vertices[i][e];
      if (!vertex_ok(v)) bad(node() + "sub-edge vertex " + std::to_string(v) + " of " + std::to_string(vertices));
      if (in(sub_edges[e].a) != in(sub_edges[e].b)) {
        crossing = true;
        if (v < 0) bad(node() + "sub-edge " + std::to_string(e) + " changes sign without a vertex");
      }
    }
    if (t.transitions.straight_faces[i] >> 6) bad(node() + "straight faces beyond the 6 faces");
    const std::int32_t centre = t.transitions.centre_vertices[i];
    if (!vertex_ok(centre) || (crossing && centre < 0))
      bad(node() + "centre vertex " + std::to_string(centre) + " of " + std::to_string(vertices));
    for (std::int32_t m : t.transitions.neighbours[i])
      if (m < -1 || (m >= 0 && std::size_t(m) >= n)) bad(node() + "neighbour " + std::to_string(m) + " of " + std::to_string(n));
  }

}

void Decoder::check_lod_array(const McOctree& t, const LodArray& lod, std::size_t internal) const {
  const std::size_t n = t.nodes.keys.size();
  // The LOD array: every internal node once, parents first (§5.2).
  if (lod.order.size() != internal)
    bad("the LOD array has " + std::to_string(lod.order.size()) + " entries for " + std::to_string(internal) +
        " internal nodes");
  if (lod.accumulated.size() != internal + 1)
    bad("the accumulation table has " + std::to_string(lod.accumulated.size()) + " entries, expected " +
        std::to_string(internal + 1));
  std::vector<std::uint8_t> expanded(n, 0);
  for (std::size_t k = 0; k < lod.order.size(); ++k) {
    const std::int32_t v = lod.order[k];
    auto entry = [k] { return "LOD array entry " + std::to_string(k) + ": "; };
    if (v < 0 || std::size_t(v) >= n || t.nodes.first_child[v] < 0)
      bad(entry() + "node " + std::to_string(v) + " is not an internal node");
    if (expanded[v]) bad(entry() + "node " + std::to_string(v) + " expands twice");
    if (k == 0 ? v != 0 : !expanded[t.nodes.parents[v]]) bad(entry() + "node " + std::to_string(v) + " expands before its parent");
    expanded[v] = 1;
  }
  for (std::size_t k = 0; k < lod.accumulated.size(); ++k)
    if (lod.accumulated[k] < 0) bad("accumulation table entry " + std::to_string(k) + " is negative");
  if (lod.pinned > lod.order.size())
    bad(std::to_string(lod.pinned) + " pinned expansions of " + std::to_string(lod.order.size()));
  for (std::size_t k = 0; k < lod.inside_steps.size(); ++k)
    if (lod.inside_steps[k] < 0 || std::size_t(lod.inside_steps[k]) >= lod.order.size() ||
        (k > 0 && lod.inside_steps[k] <= lod.inside_steps[k - 1]))
      bad("entry " + std::to_string(k) + " of the priorities not offered ('STEP') is " +
          std::to_string(lod.inside_steps[k]) + ": expected ascending numbers below " + std::to_string(lod.order.size()));
}

// Paged: `n` bytes from `offset` of the file; false when the file is shorter.
bool read_at(int fd, std::uint64_t offset, std::size_t n, std::uint8_t* into) {
  while (n > 0) {
    const ssize_t r = ::pread(fd, into, n, off_t(offset));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return false;
    into += r, offset += std::uint64_t(r), n -= std::size_t(r);
  }
  return true;
}

// A section's bytes: in the file's bytes, or (paged) read and checked now.
const std::uint8_t* Decoder::payload(const Section& s) {
  if (fd_ < 0) return data_ + s.offset;
  held_.emplace_back(std::max<std::uint64_t>(s.length, 1));
  if (!read_at(fd_, s.offset, s.length, held_.back().data()))
    fail("cannot read section " + tag_name(s.tag) + ": " + std::strerror(errno ? errno : EIO));
  bytes_read_ += s.length;
  if (model_checksum(held_.back().data(), s.length) != s.checksum)
    fail("checksum mismatch in section " + tag_name(s.tag) + " (damaged file)");
  return held_.back().data();
}

// Paged: the header, then the directory it sizes.
void Decoder::read_head() {
  head_.resize(std::min<std::size_t>(size_, kHeaderBytes));
  if (!read_at(fd_, 0, head_.size(), head_.data())) fail("cannot read the header");
  data_ = head_.data();
  read_header();
  head_.resize(std::min<std::uint64_t>(size_, directory_end_));
  if (!read_at(fd_, 0, head_.size(), head_.data())) fail("cannot read the section directory");
  data_ = head_.data();
  bytes_read_ += head_.size();
}

// 'PGIX' must lay the pages end to end over 'PGEO', each within what its
// triangles can need, with a finite box.
void Decoder::check_page_extents(const ClusterHierarchy& h, const std::vector<PageExtent>& extents) const {
  if (extents.size() != h.pages.size())
    bad("section 'PGIX' has " + std::to_string(extents.size()) + " pages, 'PAGE' " + std::to_string(h.pages.size()));
  std::uint64_t next = 0;
  for (std::size_t i = 0; i < extents.size(); ++i) {
    const PageExtent& e = extents[i];
    const std::string where = "section 'PGIX': page " + std::to_string(i) + ": ";
    if (e.offset != next || e.bytes % 8 != 0)
      bad(where + "its " + bytes_text(e.bytes) + " at " + std::to_string(e.offset) + " do not follow on from " +
          std::to_string(next));
    next += e.bytes;
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(e.min[k]) || !std::isfinite(e.max[k]) || e.min[k] > e.max[k])
        bad(where + "needs a finite box");
  }
  if (next != section("PGEO").length)
    bad("section 'PGIX': the pages hold " + bytes_text(next) + ", 'PGEO' " + bytes_text(section("PGEO").length));
}

ModelPagesHead Decoder::decode_pages_head() {
  read_head();
  read_directory();
  verify_length_and_checksums();
  index_sections();
  ModelPagesHead head;
  if (major_ < kPacked || !by_tag_.count(fourcc("CINF")) || !by_tag_.count(fourcc("PGIX")) ||
      !by_tag_.count(fourcc("PGEO")) || !by_tag_.count(fourcc("PAGE")))
    return head;
  LodModel& model = head.model;
  read_origin(&model);
  vertices_ = section("POSN").count;
  head.normals = section("NRML").count > 0;
  head.colors = section("COLR").count > 0;
  if (vertices_ > kMaxIndex) bad(std::to_string(vertices_) + " vertices, more than 32-bit indices address");
  if ((head.normals && section("NRML").count != vertices_) || (head.colors && section("COLR").count != vertices_))
    bad("normals or colours do not match the " + std::to_string(vertices_) + " vertices");
  decode_clusters(&model);
  check_page_extents(*model.clusters, records_.page_extents);
  head.extents = std::move(records_.page_extents);
  head.pages_offset = section("PGEO").offset;
  head.vertices = vertices_;
  head.bytes_read = bytes_read_;
  return head;
}

LodModel Decoder::decode() {
  read_header();
  read_directory();
  verify_length_and_checksums();
  index_sections();
  LodModel model;
  read_part(Part::kVertices, &model);
  read_origin(&model);
  vertices_ = model.vertices.size();
  check_vertices(model);
  const bool has_octree = major_ == 2 || by_tag_.count(fourcc("GRID"));
  const bool has_clusters = major_ >= 3 && by_tag_.count(fourcc("CINF"));
  if (!has_octree && !has_clusters) fail("holds no LOD structure: neither an octree ('GRID') nor clusters ('CINF')");
  if (has_clusters) decode_clusters(&model);
  if (!has_octree) return model;

  model.octree.emplace();
  McOctree& t = model.octree->tree;
  read_grid(&t);
  read_part(Part::kOctree, &model);
  if (major_ >= kPacked) unpack_octree(records_.packed, source_, &t);
  read_pinned(&model.octree->lod);
  if (!by_tag_.count(fourcc("STRF"))) t.transitions.straight_faces.assign(t.transitions.size(), 0);
  check_octree_arrays(t);
  const std::size_t internal = check_nodes(t);
  check_transitions(t, internal);
  check_lod_array(t, model.octree->lod, internal);
  return model;
}

}  // namespace

LodModel decode_model(const std::uint8_t* data, std::size_t size, const std::string& source) {
  return Decoder(data, size, source).decode();
}

ModelPagesHead read_model_pages_head(const std::string& path) {
  std::uintmax_t size = 0;
  const int fd = open_model_file(path, &size);
  const std::unique_ptr<int, void (*)(int*)> closing(new int(fd), [](int* f) { ::close(*f), delete f; });
  return Decoder(fd, std::size_t(size), path).decode_pages_head();
}

}  // namespace scan2lod
