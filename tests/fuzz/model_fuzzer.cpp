// libFuzzer target for the .mco reader: whatever decode_model accepts must
// give levels of each LOD structure it holds through the face (lod/lod_model.h:
// LevelExtractor by percent, triangles, priority, error and camera, then
// compact_level), and the octree's LodCursor, without reading out of bounds.
// Built only with clang (tests/fuzz/build.sh), under AddressSanitizer and UBSan.
//
// An input is either
// - 'R' + a whole file, whose checksums are recomputed first so that the
//   damage reaches the structure checks behind them, or
// - 'S' + edits of 9 bytes (array, index, value) applied to a seed model,
//   which is then encoded (correct checksums) and read back: damage that is
//   consistent at the byte level and wrong in meaning, in the octree's arrays,
//   the shared vertices or the cluster hierarchy's.
// The seed model is $MODEL_FUZZ_SEED (a small .mco with both structures, e.g.
// the bunny at R = 16 from scan2lod build, whose default is both).
#include <scan2lod/core/error.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/lod/octree/extract.h>
#include <scan2lod/lod/octree/lod_cursor.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

using namespace scan2lod;

namespace {

std::uint64_t get_u64(const std::uint8_t* p) {
  std::uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}
void put_u64(std::uint8_t* p, std::uint64_t v) { std::memcpy(p, &v, 8); }

// Recomputes every checksum the layout lets us find (model_file.h).
void fix_checksums(std::vector<std::uint8_t>& b) {
  constexpr std::size_t kHeader = 40, kEntry = 48;
  if (b.size() < kHeader + 8) return;
  put_u64(&b[32], model_checksum(b.data(), 32));
  std::uint32_t count;
  std::memcpy(&count, &b[16], 4);
  if (count > 4096 || kHeader + kEntry * std::size_t(count) + 8 > b.size()) return;
  for (std::size_t i = 0; i < count; ++i) {
    std::uint8_t* e = &b[kHeader + kEntry * i];
    const std::uint64_t offset = get_u64(e + 24), length = get_u64(e + 32);
    if (offset <= b.size() && length <= b.size() - offset) put_u64(e + 40, model_checksum(b.data() + offset, length));
  }
  put_u64(&b[kHeader + kEntry * count], model_checksum(&b[kHeader], kEntry * count));
  put_u64(&b[b.size() - 8], model_checksum(b.data(), b.size() - 8));
}

const LodModel& seed() {
  static const LodModel model = [] {
    const char* path = std::getenv("MODEL_FUZZ_SEED");
    if (!path) {
      std::fprintf(stderr, "model_fuzzer: set MODEL_FUZZ_SEED to a small .mco\n");
      std::abort();
    }
    LodModel m = load_model(path);
    // Both structures, and a hierarchy of several DAG levels even on a small
    // seed (or an octree-only 2.x one): small clusters over the octree's
    // full-detail mesh, which indexes the shared vertices as they are.
    if (m.octree && (!m.clusters || m.clusters->levels() < 3)) {
      LevelExtractor full(m, LodStructure::kOctree);
      TriangleMesh mesh;
      mesh.positions.assign(m.vertices.positions.begin(), m.vertices.positions.end());
      mesh.triangles = full.extract(LevelRequest::at_percent(100)).triangles;
      ClusterOptions options;
      options.cluster_triangles = 16;
      options.group_clusters = 4;
      options.threads = 1;
      add_cluster_hierarchy(&m, mesh, true, options);
    }
    if (!m.octree || !m.clusters) {
      std::fprintf(stderr, "model_fuzzer: the seed needs an octree (scan2lod build --structure both)\n");
      std::abort();
    }
    // The seed as this reader writes it, for a raw ('R') corpus entry.
    if (const char* out = std::getenv("MODEL_FUZZ_WRITE_SEED")) {
      const std::vector<std::uint8_t> bytes = encode_model(m);
      FILE* f = std::fopen(out, "wb");
      if (!f || std::fputc('R', f) == EOF || std::fwrite(bytes.data(), 1, bytes.size(), f) != bytes.size()) std::abort();
      std::fclose(f);
    }
    return m;
  }();
  return model;
}

// On a std::vector or a LargeArray (core/large_array.h).
template <class Vector>
void edit(Vector& v, std::uint32_t index, std::uint32_t value) {
  using T = typename Vector::value_type;
  if (v.empty()) return;
  auto* words = reinterpret_cast<std::uint8_t*>(v.data());
  const std::size_t bytes = v.size() * sizeof(T);
  // Values near the edges are the interesting ones: small, negative, huge.
  const std::int32_t signed_value = std::int32_t(value);
  const std::size_t width = sizeof(T) % 4 == 0 ? 4 : 1;
  const std::size_t at = (std::size_t(index) * width) % bytes / width * width;
  if (width == 4) std::memcpy(words + at, &signed_value, 4);
  else words[at] = std::uint8_t(value);
}

// Drops 1 to 4 elements from the end (all of a shorter array).
template <class Vector>
void shrink(Vector& v, std::uint32_t index) {
  v.resize(v.size() - std::min<std::size_t>(v.size(), 1 + index % 4));
}

void apply(LodModel& m, const std::uint8_t* op) {
  std::uint32_t index, value;
  std::memcpy(&index, op + 1, 4);
  std::memcpy(&value, op + 5, 4);
  const unsigned kind = op[0] % 41;
  if ((kind < 26 || kind == 40) && !m.octree) return;
  if (kind >= 30 && kind < 39 && !m.clusters) return;
  McOctree* t = m.octree ? &m.octree->tree : nullptr;
  LodArray* lod = m.octree ? &m.octree->lod : nullptr;
  ClusterHierarchy* h = m.clusters ? &*m.clusters : nullptr;
  switch (kind) {
    // The octree's arrays.
    case 0: edit(t->nodes.keys, index, value); break;
    case 1: edit(t->nodes.levels, index, value); break;
    case 2: edit(t->nodes.parents, index, value); break;
    case 3: edit(t->nodes.first_child, index, value); break;
    case 4: edit(t->nodes.child_counts, index, value); break;
    case 5: edit(t->nodes.cases, index, value); break;
    case 6: edit(t->nodes.edge_vertices, index, value); break;
    case 7: edit(t->nodes.first_triangle, index, value); break;
    case 8: edit(t->nodes.triangle_counts, index, value); break;
    case 9: edit(t->nodes.metrics, index, value); break;
    case 10: edit(t->transitions.boundary_inside, index, value); break;
    case 11: edit(t->transitions.sub_edge_vertices, index, value); break;
    case 12: edit(t->transitions.centre_vertices, index, value); break;
    case 13: edit(t->transitions.neighbours, index, value); break;
    case 14: edit(t->triangles, index, value); break;
    case 15: edit(t->patches.triangles, index, value); break;
    case 16: edit(t->patches.group_first, index, value); break;
    case 17: edit(t->patches.needs_first, index, value); break;
    case 18: edit(t->patches.needs, index, value); break;
    case 19: {  // the cube size, as a chosen float
      float f;
      std::memcpy(&f, &value, 4);
      t->grid.cube_size = f;
      break;
    }
    case 20: edit(lod->order, index, value); break;
    case 21: edit(lod->accumulated, index, value); break;
    case 22: lod->pinned = value; break;
    case 23: t->grid.resolution = std::int32_t(value); break;
    case 24: t->depth = std::int32_t(value); break;
    case 25: t->mesh_vertices = value; break;
    // The shared vertices.
    case 26: edit(m.vertices.positions, index, value); break;
    case 27: edit(m.vertices.normals, index, value); break;
    case 28:
      shrink(m.vertices.positions, index);
      break;
    case 29: edit(m.vertices.colors, index, value); break;
    // The cluster hierarchy's arrays (Cluster and GroupBound by 4-byte words:
    // first triangle, count/level/reserved, own and parent group; centre,
    // radius and error).
    case 30: edit(h->clusters, index, value); break;
    case 31: edit(h->triangles, index, value); break;
    case 32: edit(h->groups, index, value); break;
    case 33: h->full_triangles = std::int64_t(std::int32_t(value)); break;
    case 34: m.cluster_vertex_first = value; break;
    case 35: m.cluster_vertex_count = value; break;
    case 36:
      shrink(h->clusters, index);
      break;
    case 37:
      shrink(h->groups, index);
      break;
    case 38: {  // a group's error set to a chosen float (NaN, 0, tiny, huge, negative)
      if (h->groups.empty()) break;
      float f;
      std::memcpy(&f, &value, 4);
      h->groups[index % h->groups.size()].error = f;
      break;
    }
    // Structures dropped: a model of one.
    case 39:
      if (index % 2) m.octree.reset();
      else m.clusters.reset();
      break;
    // Added with format 4.2.
    case 40: edit(t->transitions.straight_faces, index, value); break;
  }
}

// A level's indices must name the model's vertices; compact_level reads them.
void check_level(const LodModel& m, const std::vector<Triangle>& triangles) {
  for (const Triangle& t : triangles)
    for (const std::int32_t v : t)
      if (v < 0 || std::size_t(v) >= m.vertices.size()) {
        std::fprintf(stderr, "model_fuzzer: a level names vertex %d of %zu\n", v, m.vertices.size());
        std::abort();
      }
  compact_level(m, triangles);
}

void extract_everything(const LodModel& m) {
  if (m.octree) {
    LevelExtractor octree(m, LodStructure::kOctree);
    const LodArray& lod = m.octree->lod;
    const std::size_t full = lod.full();
    for (const double percent : {0.0, 1.0, 33.0, 50.0, 100.0})
      check_level(m, octree.extract(LevelRequest::at_percent(percent)).triangles);
    for (const std::size_t p : {std::size_t(0), lod.pinned, full / 3, full / 2, full})
      if (p <= full) check_level(m, octree.extract(LevelRequest::at_priority(p)).triangles);
    check_level(m, octree.extract(LevelRequest::at_triangles(octree.full_triangles() / 2)).triangles);
    octree.triangle_levels();
    LodCursor cursor(m.octree->tree, lod);
    for (const std::size_t p : {full, full / 2, std::size_t(1), full / 3 + 1, std::size_t(0)}) {
      cursor.move_to(p);
      check_level(m, cursor.buffer());
    }
  }
  if (m.clusters) {
    LevelExtractor clusters(m, LodStructure::kClusters);
    for (const double percent : {0.0, 1.0, 33.0, 50.0, 100.0}) {
      check_level(m, clusters.extract(LevelRequest::at_percent(percent)).triangles);
      clusters.triangle_levels();
    }
    check_level(m, clusters.extract(LevelRequest::at_triangles(clusters.full_triangles() / 3)).triangles);
    const std::vector<GroupBound>& groups = m.clusters->groups;
    const double some = groups.empty() ? 1.0 : double(groups[groups.size() / 2].error);
    for (const double error : {0.0, some, 1e30, -1.0, double(NAN)})
      check_level(m, clusters.extract(LevelRequest::at_error(error)).triangles);
    const Aabb box = model_bounds(m);
    const Vec3f centre = box.empty() ? Vec3f::Zero() : Vec3f(0.5f * (box.min + box.max));
    const float far = box.empty() ? 1.f : 2.f * box.diagonal() + 1.f;
    CameraView camera;
    camera.target = centre;
    // Far off, inside every sphere (next to the centre), and from below.
    for (const Vec3f& eye : {Vec3f(centre + Vec3f(0, 0, far)), Vec3f(centre + Vec3f(0, 0, 1e-3f * far)),
                             Vec3f(centre - Vec3f(far, far, 0))}) {
      camera.eye = eye;
      for (const double pixels : {0.5, 4.0})
        check_level(m, clusters.extract(LevelRequest::for_camera(camera, pixels)).triangles);
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  seed();  // built once, before the first input (and written out if asked)
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  std::vector<std::uint8_t> bytes;
  if (data[0] == 'S') {
    LodModel m = seed();
    for (std::size_t at = 1; at + 9 <= size; at += 9) apply(m, data + at);
    // Format 3 stores every array whole, so each edit reaches the reader
    // (format 4 derives most of them; raw 'R' entries reach its packing).
    bytes = encode_model(m, 3);
  } else if (data[0] == 'R') {
    bytes.assign(data + 1, data + size);
    fix_checksums(bytes);
  } else {
    return 0;
  }
  try {
    const LodModel model = decode_model(bytes.data(), bytes.size(), "fuzz.mco");
    extract_everything(model);
  } catch (const InputError&) {
  }
  return 0;
}
