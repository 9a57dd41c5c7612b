// The .mco model file (lod/model_file.h): a saved model comes back exactly,
// both LOD structures (the octree and the cluster hierarchy) down to the
// triangles of every level of detail, and a truncated, damaged, newer, older
// or crafted file ends in an InputError that says what is wrong, never in a
// crash or an out-of-bounds read.
#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/core/error.h>
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/lod/octree/extract.h>
#include <scan2lod/lod/octree/octree_order.h>
#include <scan2lod/measure/surface_distance.h>
#include <scan2lod/measure/topology.h>
#include <scan2lod/reconstruct/cube_table.h>
#include <scan2lod/reconstruct/marching_cubes.h>

#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>

using namespace scan2lod;
namespace fs = std::filesystem;

namespace {

const LodModel& bunny64() {
  static const LodModel model = [] {
    const OrientedPoints points = load_oriented_points({std::string(SCAN2LOD_SOURCE_DIR) + "/data/bunny/bun.conf"});
    ReconstructOptions options;
    options.resolution = 64;
    const Reconstruction r = reconstruct(points, options);
    McOctree tree = build_mc_octree(r);
    LodArray lod = number_nodes(tree);
    // Both structures over one vertex array: the mesh is the octree's first vertices.
    LodModel m = model_from_octree(std::move(tree), std::move(lod));
    add_cluster_hierarchy(&m, r.mesh, true);
    return m;
  }();
  return model;
}

const OctreeLod& octree() { return *bunny64().octree; }
const ClusterHierarchy& clusters() { return *bunny64().clusters; }

const std::vector<std::uint8_t>& bunny64_bytes() {
  static const std::vector<std::uint8_t> bytes = encode_model(bunny64());
  return bytes;
}

fs::path scratch() {
  const fs::path dir = scan2lod::testing::scratch_folder() / "model_file";
  fs::create_directories(dir);
  return dir;
}

// The message of the InputError that decoding the first `size` bytes throws,
// or "" when they decode.
std::string error_of(const std::uint8_t* data, std::size_t size) {
  try {
    decode_model(data, size, "m.mco");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::uint32_t u32_at(const std::vector<std::uint8_t>& b, std::size_t at) {
  std::uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}
std::uint64_t u64_at(const std::vector<std::uint8_t>& b, std::size_t at) {
  std::uint64_t v;
  std::memcpy(&v, b.data() + at, 8);
  return v;
}
void set_u32(std::vector<std::uint8_t>* b, std::size_t at, std::uint32_t v) { std::memcpy(b->data() + at, &v, 4); }
void set_u64(std::vector<std::uint8_t>* b, std::size_t at, std::uint64_t v) { std::memcpy(b->data() + at, &v, 8); }

// A file's sections as the layout in model_file.h describes them.
struct RawSection {
  std::uint32_t tag, flags, element_size;
  std::uint64_t count;
  std::vector<std::uint8_t> payload;
};

std::vector<RawSection> split(const std::vector<std::uint8_t>& b) {
  std::vector<RawSection> out;
  for (std::uint32_t i = 0; i < u32_at(b, 16); ++i) {
    const std::size_t e = 40 + 48 * std::size_t(i);
    const std::uint64_t offset = u64_at(b, e + 24), length = u64_at(b, e + 32);
    out.push_back({u32_at(b, e), u32_at(b, e + 4), u32_at(b, e + 8), u64_at(b, e + 16),
                   std::vector<std::uint8_t>(b.begin() + std::ptrdiff_t(offset), b.begin() + std::ptrdiff_t(offset + length))});
  }
  return out;
}

// Lays sections out again with fresh offsets and checksums.
std::vector<std::uint8_t> join(const std::vector<RawSection>& sections, std::uint32_t major, std::uint32_t minor) {
  const std::size_t directory_end = 40 + 48 * sections.size() + 8;
  std::size_t length = directory_end;
  for (const RawSection& s : sections) length = (length + s.payload.size() + 7) & ~std::size_t(7);
  length += 8;
  std::vector<std::uint8_t> b(length, 0);
  std::memcpy(b.data(), "SCAN2LOD", 8);
  set_u32(&b, 8, major);
  set_u32(&b, 12, minor);
  set_u32(&b, 16, std::uint32_t(sections.size()));
  set_u64(&b, 24, length);
  set_u64(&b, 32, model_checksum(b.data(), 32));
  std::size_t offset = directory_end;
  for (std::size_t i = 0; i < sections.size(); ++i) {
    const RawSection& s = sections[i];
    const std::size_t e = 40 + 48 * i;
    set_u32(&b, e, s.tag);
    set_u32(&b, e + 4, s.flags);
    set_u32(&b, e + 8, s.element_size);
    set_u64(&b, e + 16, s.count);
    set_u64(&b, e + 24, offset);
    set_u64(&b, e + 32, s.payload.size());
    set_u64(&b, e + 40, model_checksum(s.payload.data(), s.payload.size()));
    if (!s.payload.empty()) std::memcpy(b.data() + offset, s.payload.data(), s.payload.size());
    offset = (offset + s.payload.size() + 7) & ~std::size_t(7);
  }
  set_u64(&b, directory_end - 8, model_checksum(b.data() + 40, 48 * sections.size()));
  set_u64(&b, length - 8, model_checksum(b.data(), length - 8));
  return b;
}

std::uint32_t tag(const char (&s)[5]) {
  std::uint32_t v;
  std::memcpy(&v, s, 4);
  return v;
}

// Where the section `t` is among a file's sections (its directory entry).
std::size_t index_of(const std::vector<RawSection>& sections, std::uint32_t t) {
  for (std::size_t i = 0; i < sections.size(); ++i)
    if (sections[i].tag == t) return i;
  ADD_FAILURE() << "no section " << std::string(reinterpret_cast<const char*>(&t), 4);
  return 0;
}
std::size_t index_of(const std::vector<std::uint8_t>& b, std::uint32_t t) {
  for (std::uint32_t i = 0; i < u32_at(b, 16); ++i)
    if (u32_at(b, 40 + 48 * std::size_t(i)) == t) return i;
  ADD_FAILURE() << "no section " << std::string(reinterpret_cast<const char*>(&t), 4);
  return 0;
}
// A section's payload: [offset, offset + length).
std::uint64_t payload_offset(const std::vector<std::uint8_t>& b, std::uint32_t t) {
  return u64_at(b, 40 + 48 * index_of(b, t) + 24);
}
std::uint64_t payload_length(const std::vector<std::uint8_t>& b, std::uint32_t t) {
  return u64_at(b, 40 + 48 * index_of(b, t) + 32);
}

std::vector<Triangle> extract(const OctreeLod& m, double percent) {
  std::vector<std::uint8_t> scratch;
  std::vector<Triangle> tris;
  extract_lod(m.tree, m.lod, priority_for_percent(m.lod, percent), &scratch, &tris);
  return tris;
}

// The triangles of a level through the face (lod/lod_model.h).
std::vector<Triangle> level(const LodModel& m, LodStructure s, const LevelRequest& request) {
  LevelExtractor extractor(m, s);
  return extractor.extract(request).triangles;
}

bool same_clusters(const ClusterHierarchy& a, const ClusterHierarchy& b) {
  if (a.clusters.size() != b.clusters.size() || a.groups.size() != b.groups.size()) return false;
  for (std::size_t c = 0; c < a.clusters.size(); ++c) {
    const Cluster &x = a.clusters[c], &y = b.clusters[c];
    if (x.first_triangle != y.first_triangle || x.triangle_count != y.triangle_count || x.level != y.level ||
        x.reserved != y.reserved || x.own_group != y.own_group || x.parent_group != y.parent_group)
      return false;
  }
  for (std::size_t g = 0; g < a.groups.size(); ++g)  // bit for bit
    if (std::memcmp(&a.groups[g], &b.groups[g], sizeof(GroupBound)) != 0) return false;
  return a.triangles == b.triangles && a.full_triangles == b.full_triangles;
}

// A model's bytes with the header's major version replaced, its header and
// whole-file checksums recomputed (the section checksums do not cover it).
std::vector<std::uint8_t> with_major(std::vector<std::uint8_t> b, std::uint32_t major) {
  set_u32(&b, 8, major);
  set_u64(&b, 32, model_checksum(b.data(), 32));
  set_u64(&b, b.size() - 8, model_checksum(b.data(), b.size() - 8));
  return b;
}

}  // namespace

TEST(ModelFile, ChecksumIsXxh64) {
  // Reference values from the xxHash library (libxxhash 0.8.1, XXH64).
  std::vector<std::uint8_t> long_input;
  for (int r = 0; r < 2; ++r)
    for (int i = 0; i < 256; ++i) long_input.push_back(std::uint8_t(i));
  for (char c : std::string("xyz")) long_input.push_back(std::uint8_t(c));
  EXPECT_EQ(model_checksum("", 0), 0xef46db3751d8e999ull);
  EXPECT_EQ(model_checksum("a", 1), 0xd24ec4f1a98c6e5bull);
  EXPECT_EQ(model_checksum("abc", 3), 0x44bc2cf5ad770999ull);
  EXPECT_EQ(model_checksum("scan2lod", 8), 0x11a098d921d7874bull);
  EXPECT_EQ(model_checksum(long_input.data(), long_input.size()), 0x4b52ca150d7d875full);
  EXPECT_EQ(model_checksum("abc", 3, 0x9E3779B1), 0x1318df30094a85fdull);
  EXPECT_EQ(model_checksum(long_input.data(), long_input.size(), 0x9E3779B1), 0x423be70ddf548b88ull);
}

TEST(ModelFile, RoundTripKeepsEveryArrayAndEveryLevelOfDetail) {
  const LodModel& m = bunny64();
  const fs::path dir = scratch() / "round_trip";
  fs::create_directories(dir);
  const fs::path path = dir / "bunny.mco";
  save_model(path.string(), m);
  EXPECT_EQ(std::size_t(std::distance(fs::directory_iterator(dir), fs::directory_iterator())), 1u)
      << "a temporary file was left behind";
  EXPECT_EQ(fs::file_size(path), bunny64_bytes().size());
  const LodModel l = load_model(path.string());
  ASSERT_TRUE(l.octree && l.clusters);

  const McOctree &a = m.octree->tree, &b = l.octree->tree;
  EXPECT_EQ(a.grid.origin, b.grid.origin);
  EXPECT_EQ(a.grid.cube_size, b.grid.cube_size);
  EXPECT_EQ(a.grid.resolution, b.grid.resolution);
  EXPECT_EQ(a.depth, b.depth);
  EXPECT_EQ(a.mesh_vertices, b.mesh_vertices);
  EXPECT_EQ(a.nodes.keys, b.nodes.keys);
  EXPECT_EQ(a.nodes.levels, b.nodes.levels);
  EXPECT_EQ(a.nodes.parents, b.nodes.parents);
  EXPECT_EQ(a.nodes.first_child, b.nodes.first_child);
  EXPECT_EQ(a.nodes.child_counts, b.nodes.child_counts);
  EXPECT_EQ(a.nodes.cases, b.nodes.cases);
  EXPECT_EQ(a.nodes.edge_vertices, b.nodes.edge_vertices);
  EXPECT_EQ(a.nodes.first_triangle, b.nodes.first_triangle);
  EXPECT_EQ(a.nodes.triangle_counts, b.nodes.triangle_counts);
  EXPECT_EQ(a.nodes.metrics, b.nodes.metrics);
  EXPECT_EQ(a.transitions.boundary_inside, b.transitions.boundary_inside);
  EXPECT_EQ(a.transitions.sub_edge_vertices, b.transitions.sub_edge_vertices);
  EXPECT_EQ(a.transitions.centre_vertices, b.transitions.centre_vertices);
  EXPECT_EQ(a.transitions.neighbours, b.transitions.neighbours);
  EXPECT_EQ(a.transitions.straight_faces, b.transitions.straight_faces);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.patches.triangles, b.patches.triangles);
  EXPECT_EQ(a.patches.group_first, b.patches.group_first);
  EXPECT_EQ(a.patches.needs_first, b.patches.needs_first);
  EXPECT_EQ(a.patches.needs, b.patches.needs);
  // The tree's own vertex arrays stay empty in a model: its vertices are the model's.
  EXPECT_TRUE(b.vertices.positions.empty() && b.vertices.normals.empty() && b.vertices.colors.empty());
  EXPECT_FALSE(m.vertices.positions.empty());
  EXPECT_EQ(m.vertices.positions, l.vertices.positions);
  EXPECT_EQ(m.vertices.normals, l.vertices.normals);
  EXPECT_EQ(m.vertices.colors, l.vertices.colors);
  const LodArray &ma = m.octree->lod, &la = l.octree->lod;
  EXPECT_EQ(ma.order, la.order);
  EXPECT_EQ(ma.accumulated, la.accumulated);
  EXPECT_EQ(ma.pinned, la.pinned);
  EXPECT_FALSE(ma.inside_steps.empty());
  EXPECT_EQ(ma.inside_steps, la.inside_steps);

  for (double percent : {0.0, 1.0, 10.0, 50.0, 100.0}) {
    const std::vector<Triangle> original = extract(*m.octree, percent), loaded = extract(*l.octree, percent);
    EXPECT_EQ(original, loaded) << percent << "%";
    EXPECT_EQ(std::int64_t(loaded.size()), la.accumulated[priority_for_percent(la, percent)]) << percent << "%";
  }
  EXPECT_GT(extract(*l.octree, 100).size(), 10000u);
  // Deterministic: the loaded model writes the same bytes.
  EXPECT_EQ(encode_model(l), bunny64_bytes());
}

TEST(ModelFile, TruncatedFilesAreRejectedNamingWhere) {
  const std::vector<std::uint8_t>& bytes = bunny64_bytes();
  const std::size_t directory_end = 40 + 48 * std::size_t(u32_at(bytes, 16)) + 8;
  std::uint64_t last_payload_end = 0;
  for (std::uint32_t i = 0; i < u32_at(bytes, 16); ++i)
    last_payload_end = std::max(last_payload_end, u64_at(bytes, 40 + 48 * i + 24) + u64_at(bytes, 40 + 48 * i + 32));
  std::vector<std::size_t> lengths;
  for (std::size_t n = 0; n <= 64; ++n) lengths.push_back(n);
  for (std::size_t n = 64; n < bytes.size(); n += 293) lengths.push_back(n);
  for (std::size_t n = directory_end - 2; n <= directory_end + 2; ++n) lengths.push_back(n);
  for (std::size_t k = 1; k <= 16; ++k) lengths.push_back(bytes.size() - k);
  std::size_t named = 0;
  for (std::size_t n : lengths) {
    const std::string error = error_of(bytes.data(), n);
    ASSERT_FALSE(error.empty()) << n << " bytes decoded";
    EXPECT_EQ(error.rfind("m.mco: ", 0), 0u) << error;
    if (n == 0) {
      EXPECT_NE(error.find("empty"), std::string::npos) << error;
      continue;
    }
    EXPECT_NE(error.find("truncated"), std::string::npos) << n << ": " << error;
    if (n >= directory_end && n < last_payload_end) {
      EXPECT_NE(error.find("truncated in section '"), std::string::npos) << n << ": " << error;
      ++named;
    }
  }
  EXPECT_GT(named, 1000u);
  // Through a real file, the message names it.
  const fs::path path = scratch() / "cut.mco";
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size() / 2));
  try {
    load_model(path.string());
    FAIL() << "a half file loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path.string() + ": truncated in section '"), std::string::npos) << e.what();
  }
}

TEST(ModelFile, FlippedBytesAreCaughtByChecksums) {
  std::vector<std::uint8_t> bytes = bunny64_bytes();
  const std::size_t directory_end = 40 + 48 * std::size_t(u32_at(bytes, 16)) + 8;
  std::vector<std::size_t> positions;
  for (std::size_t p = 0; p < directory_end + 64; ++p) positions.push_back(p);
  for (std::size_t p = directory_end + 64; p < bytes.size(); p += 997) positions.push_back(p);
  for (std::size_t k = 1; k <= 16; ++k) positions.push_back(bytes.size() - k);
  for (std::size_t p : positions) {
    const std::uint8_t flip = std::uint8_t(1u << (p % 8));
    bytes[p] ^= flip;
    const std::string error = error_of(bytes.data(), bytes.size());
    bytes[p] ^= flip;
    ASSERT_FALSE(error.empty()) << "a flipped byte at " << p << " went unnoticed";
    if (p < 8)
      EXPECT_NE(error.find("not a scan2lod model"), std::string::npos) << p << ": " << error;
    else
      EXPECT_NE(error.find("checksum mismatch"), std::string::npos) << p << ": " << error;
  }
  // A flip inside a payload names its section.
  const std::size_t edges_offset = std::size_t(payload_offset(bytes, tag("EDGP")));
  bytes[edges_offset + 5] ^= 0x10;
  EXPECT_NE(error_of(bytes.data(), bytes.size()).find("checksum mismatch in section 'EDGP'"), std::string::npos);
}

TEST(ModelFile, NewerMajorVersionIsRejectedAsNewer) {
  std::vector<std::uint8_t> bytes = join(split(bunny64_bytes()), kModelFormatMajor + 1, 0);
  const std::string error = error_of(bytes.data(), bytes.size());
  EXPECT_NE(error.find("newer scan2lod"), std::string::npos) << error;
  EXPECT_NE(error.find("format " + std::to_string(kModelFormatMajor + 1)), std::string::npos) << error;
  EXPECT_NE(error.find("reads up to " + std::to_string(kModelFormatMajor)), std::string::npos) << error;
  // Only the header needs to be readable to tell: even a short newer file says so.
  EXPECT_NE(error_of(bytes.data(), 40).find("newer scan2lod"), std::string::npos);
}

TEST(ModelFile, NewerMinorVersionsAddSectionsOldReadersSkip) {
  // The layout in model_file.h rebuilt by hand gives the same bytes.
  ASSERT_EQ(join(split(bunny64_bytes()), kModelFormatMajor, kModelFormatMinor), bunny64_bytes());
  std::vector<RawSection> sections = split(bunny64_bytes());
  sections.insert(sections.begin() + 3, RawSection{tag("XTRA"), 0, 4, 3, std::vector<std::uint8_t>(12, 7)});
  const std::vector<std::uint8_t> optional = join(sections, kModelFormatMajor, kModelFormatMinor + 1);
  const LodModel l = decode_model(optional.data(), optional.size(), "m.mco");
  EXPECT_EQ(encode_model(l), bunny64_bytes());
  // One a reader must understand is refused, by name.
  sections[3].flags = 1;
  const std::vector<std::uint8_t> required = join(sections, kModelFormatMajor, kModelFormatMinor + 1);
  const std::string error = error_of(required.data(), required.size());
  EXPECT_NE(error.find("'XTRA'"), std::string::npos) << error;
  EXPECT_NE(error.find("newer scan2lod"), std::string::npos) << error;
  // A known section missing or twice.
  sections.erase(sections.begin() + 3);
  std::vector<RawSection> missing = sections, twice = sections;
  const std::size_t levl = index_of(sections, tag("CASE"));
  missing.erase(missing.begin() + std::ptrdiff_t(levl));
  twice.push_back(twice[levl]);
  std::vector<std::uint8_t> b = join(missing, kModelFormatMajor, kModelFormatMinor);
  EXPECT_NE(error_of(b.data(), b.size()).find("missing section 'CASE'"), std::string::npos) << error_of(b.data(), b.size());
  b = join(twice, kModelFormatMajor, kModelFormatMinor);
  EXPECT_NE(error_of(b.data(), b.size()).find("'CASE' appears twice"), std::string::npos);
}

TEST(ModelFile, BadMagicIsNotAModel) {
  std::vector<std::uint8_t> bytes = bunny64_bytes();
  bytes[0] = 'X';
  EXPECT_NE(error_of(bytes.data(), bytes.size()).find("not a scan2lod model (.mco): bad magic"), std::string::npos);
  EXPECT_NE(error_of(bytes.data(), 3).find("bad magic"), std::string::npos);
  // A mesh is not a model.
  TriangleMesh mesh;
  mesh.positions = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)};
  mesh.triangles = {{0, 1, 2}};
  const fs::path ply = scratch() / "mesh.ply";
  write_mesh(ply.string(), mesh);
  try {
    load_model(ply.string());
    FAIL() << "a PLY loaded as a model";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(ply.string() + ": not a scan2lod model"), std::string::npos) << e.what();
  }
}

TEST(ModelFile, CraftedContentsAreRejectedBeforeExtraction) {
  // Checksums cannot stop a crafted file: its indices are checked too.
  struct Case {
    std::string what, expect;
    std::function<void(LodModel&)> craft;
  };
  const LodModel& m = bunny64();
  const McOctree& tree = octree().tree;
  const std::int32_t n = std::int32_t(tree.size());
  const std::int32_t vertices = std::int32_t(m.vertices.size());
  std::int32_t leaf = 0;
  while (!tree.is_leaf(std::size_t(leaf))) ++leaf;
  const std::vector<Case> cases = {
      {"a per-node array one short", "'LEVL' has", [](LodModel& l) { l.octree->tree.nodes.levels.pop_back(); }},
      {"children past the nodes", "children", [n](LodModel& l) {
         l.octree->tree.nodes.first_child[1] = n - 1;
         l.octree->tree.nodes.child_counts[1] = 8;
       }},
      {"a parent out of range", "child 5 does not lie inside it", [n](LodModel& l) { l.octree->tree.nodes.parents[5] = n + 100; }},
      {"a triangle range past TRIS", "triangles", [](LodModel& l) {
         l.octree->tree.nodes.first_triangle.back() = std::int32_t(l.octree->tree.triangles.size());
         l.octree->tree.nodes.triangle_counts.back() = 1;
       }},
      {"a triangle naming a missing vertex", "names vertex", [vertices](LodModel& l) { l.octree->tree.triangles[7][1] = vertices; }},
      {"a negative vertex in a patch", "'PTRI'", [](LodModel& l) {
         l.octree->tree.patches.triangles.push_back({0, -3, 1});
       }},
      {"an edge vertex out of range", "edge vertex", [vertices](LodModel& l) { l.octree->tree.nodes.edge_vertices.back()[0] = vertices; }},
      {"a neighbour out of range", "neighbour", [n](LodModel& l) { l.octree->tree.transitions.neighbours[2][4] = n; }},
      {"a crossing without a vertex", "without a vertex", [](LodModel& l) {
         for (auto& s : l.octree->tree.transitions.sub_edge_vertices) s.fill(-1);
       }},
      {"a patch group past the patches", "'PGRP'", [](LodModel& l) { l.octree->tree.patches.group_first.back() += 1; }},
      {"a patch needing a missing node", "'PNDS' names node", [n](LodModel& l) {
         l.octree->tree.patches.needs.push_back(n);
         l.octree->tree.patches.needs_first.back() += 1;
       }},
      {"normals for too few vertices", "normals", [](LodModel& l) { l.vertices.normals.pop_back(); }},
      {"a leaf in the LOD array", "not an internal node", [leaf](LodModel& l) { l.octree->lod.order[3] = leaf; }},
      {"a node expanded twice", "expands twice", [](LodModel& l) { l.octree->lod.order[4] = l.octree->lod.order[3]; }},
      {"a child before its parent", "before its parent", [](LodModel& l) { std::swap(l.octree->lod.order[1], l.octree->lod.order.back()); }},
      {"an accumulation table too short", "accumulation table", [](LodModel& l) { l.octree->lod.accumulated.pop_back(); }},
      {"a resolution that is not 2^depth", "resolution", [](LodModel& l) { l.octree->tree.grid.resolution = 100; }},
      {"mesh_vertices past the vertices", "mesh_vertices", [](LodModel& l) { l.octree->tree.mesh_vertices = 1u << 30; }},
      {"a pinned prefix past the LOD array", "pinned expansions", [](LodModel& l) { l.octree->lod.pinned = l.octree->lod.order.size() + 1; }},
      {"priorities not offered out of order", "('STEP')", [](LodModel& l) { std::swap(l.octree->lod.inside_steps[0], l.octree->lod.inside_steps[1]); }},
      {"a priority not offered past the array", "('STEP')", [](LodModel& l) { l.octree->lod.inside_steps.back() = std::int32_t(l.octree->lod.order.size()); }},
      {"a straight face past the six", "straight faces", [](LodModel& l) { l.octree->tree.transitions.straight_faces[2] = 64; }},
      {"straight faces one short", "'STRF' has", [](LodModel& l) { l.octree->tree.transitions.straight_faces.pop_back(); }},
  };
  for (const Case& c : cases) {
    LodModel crafted = m;
    c.craft(crafted);
    // In format 3, which stores these arrays whole (format 4 derives most).
    const std::vector<std::uint8_t> bytes = encode_model(crafted, 3);
    const std::string error = error_of(bytes.data(), bytes.size());
    EXPECT_NE(error.find("inconsistent model"), std::string::npos) << c.what << ": " << error;
    EXPECT_NE(error.find(c.expect), std::string::npos) << c.what << ": " << error;
  }
  // Huge counts are refused by the file's size, before any allocation.
  std::vector<RawSection> sections = split(bunny64_bytes());
  sections[index_of(sections, tag("EDGP"))].count = std::uint64_t(1) << 62;  // 2^64 bytes: overflows
  std::vector<std::uint8_t> huge = join(sections, kModelFormatMajor, kModelFormatMinor);
  std::string error = error_of(huge.data(), huge.size());
  EXPECT_NE(error.find("section 'EDGP': 4611686018427387904 elements of 4 bytes"), std::string::npos) << error;
  huge = bunny64_bytes();
  const std::size_t keys = 40 + 48 * index_of(huge, tag("EDGP"));
  set_u64(&huge, keys + 16, std::uint64_t(1) << 41);
  set_u64(&huge, keys + 32, std::uint64_t(1) << 43);
  const std::size_t directory = 48 * std::size_t(u32_at(huge, 16));
  set_u64(&huge, 40 + directory, model_checksum(huge.data() + 40, directory));
  error = error_of(huge.data(), huge.size());
  EXPECT_NE(error.find("section 'EDGP': its 8796093022208 bytes"), std::string::npos) << error;
  EXPECT_NE(error.find("outside"), std::string::npos) << error;
}

TEST(ModelFile, WritesOnlyModelsIntoFoldersThatExist) {
  const fs::path dir = scratch() / "out";
  fs::create_directories(dir);
  auto message = [&](const std::string& path) -> std::string {
    try {
      save_model(path, bunny64());
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message((dir / "model.ply").string()).find(".mco"), std::string::npos);
  EXPECT_NE(message((dir / "nowhere" / "model.mco").string()).find("does not exist"), std::string::npos);
  EXPECT_TRUE(fs::is_empty(dir));
  try {
    load_model((dir / "absent.mco").string());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("absent.mco: cannot read the model: no such file"), std::string::npos);
  }
  try {
    load_model(dir.string());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos);
  }
}

TEST(ModelFile, Format1FilesAreRejectedWithARebuildHintAndFormat2FilesLoad) {
  // 1.x transitions fanned every loop around the centre: their accumulation
  // tables do not count what this extraction emits.
  for (const std::uint32_t minor : {0u, 1u}) {
    const std::vector<std::uint8_t> old = join(split(bunny64_bytes()), 1, minor);
    try {
      decode_model(old.data(), old.size(), "old.mco");
      ADD_FAILURE() << "a format 1." << minor << " file loaded";
    } catch (const InputError& e) {
      const std::string error = e.what();
      EXPECT_NE(error.find("old.mco"), std::string::npos) << error;
      EXPECT_NE(error.find("format 1." + std::to_string(minor)), std::string::npos) << error;
      EXPECT_NE(error.find("rebuild the model"), std::string::npos) << error;
    }
  }
}

// A 4.1 file has no straight faces (STRF): its accumulation table was
// counted with none, and it loads with none.
TEST(ModelFile, A41FileLoadsWithoutStraightFaces) {
  std::vector<RawSection> sections = split(bunny64_bytes());
  sections.erase(sections.begin() + std::ptrdiff_t(index_of(sections, tag("STRF"))));
  const std::vector<std::uint8_t> old = join(sections, kModelFormatMajor, 1);
  const LodModel l = decode_model(old.data(), old.size(), "old.mco");
  const OctreeTransitions& t = l.octree->tree.transitions;
  EXPECT_EQ(t.straight_faces.size(), t.size());
  EXPECT_EQ(std::count(t.straight_faces.begin(), t.straight_faces.end(), 0), std::ptrdiff_t(t.size()));
  for (double percent : {0.0, 25.0, 100.0}) {
    const std::vector<Triangle> level = extract(*l.octree, percent);
    EXPECT_EQ(std::int64_t(level.size()), l.octree->lod.accumulated[priority_for_percent(l.octree->lod, percent)]);
  }
}

// A 4.2 file has no own cuts (OWNC): its internal nodes' polygons are cut
// as the case table cuts them, on the same outlines, so every level has the
// same count and the same topology; the build's own cuts lie nearer the
// full mesh at the coarse budgets (measured at R = 64: 3.09 / 1.44 / 0.62
// against 3.29 / 1.63 / 0.71 in 1e-3 of the diagonal at 1k / 2k / 5k).
TEST(ModelFile, A42FileCutsTheCoarsePolygonsAsTheCaseTableDoes) {
  std::vector<RawSection> sections = split(bunny64_bytes());
  sections.erase(sections.begin() + std::ptrdiff_t(index_of(sections, tag("OWNC"))));
  const std::vector<std::uint8_t> old = join(sections, kModelFormatMajor, 2);
  const LodModel l = decode_model(old.data(), old.size(), "old.mco");
  const McOctree& tree = l.octree->tree;
  const auto& cases = cube_cases();
  std::size_t differ = 0;
  for (std::size_t node = 0; node < tree.internal_nodes(); ++node) {
    const CubeCase& cc = cases[tree.nodes.cases[node]];
    const auto& ev = tree.nodes.edge_vertices[node];
    ASSERT_EQ(tree.nodes.triangle_counts[node], cc.triangle_count) << node;
    for (int t = 0; t < cc.triangle_count; ++t) {
      const std::size_t at = std::size_t(tree.nodes.first_triangle[node] + t);
      EXPECT_EQ(tree.triangles[at], (Triangle{ev[cc.triangles[t][0]], ev[cc.triangles[t][1]], ev[cc.triangles[t][2]]}));
      differ += tree.triangles[at] != octree().tree.triangles[at];
    }
  }
  EXPECT_GT(differ, tree.internal_nodes() / 10) << "the build cut few polygons its own way";
  TriangleMesh full;
  full.positions.assign(l.vertices.positions.begin(), l.vertices.positions.end());
  full.triangles = extract(*l.octree, 100.0);
  EXPECT_EQ(full.triangles, extract(octree(), 100.0)) << "the leaves are the reconstruction's";
  const MeshTopology whole = mesh_topology(full);
  for (const std::int64_t budget : {1000, 2000, 5000}) {
    const std::size_t p = priority_for_triangles(l.octree->lod, budget);
    ASSERT_EQ(p, priority_for_triangles(octree().lod, budget));
    double error[2];
    for (const OctreeLod* o : {&*l.octree, &octree()}) {
      std::vector<std::uint8_t> scratch;
      TriangleMesh level;
      level.positions = full.positions;
      extract_lod(o->tree, o->lod, p, &scratch, &level.triangles);
      const MeshTopology t = mesh_topology(level);
      EXPECT_EQ(std::int64_t(level.triangles.size()), o->lod.accumulated[p]);
      EXPECT_LE(t.boundary_loops, whole.boundary_loops) << budget;
      EXPECT_LE(t.components, whole.components) << budget;
      EXPECT_EQ(t.non_manifold_edges, 0u) << budget;
      EXPECT_EQ(t.degenerate_triangles, 0u) << budget;
      const SurfaceComparison c = compare_surfaces(level, full);
      error[o == &octree()] = (c.a_to_b.mean + c.b_to_a.mean) / 2 / c.diagonal;
    }
    std::printf("%lld triangles: %.3g with the case table's cuts, %.3g with the build's (of the diagonal)\n",
                static_cast<long long>(budget), error[0], error[1]);
    EXPECT_LT(error[1], 0.97 * error[0]) << budget;
  }
}

// (continued) Own cuts that do not fit the nodes are refused, naming the
// section and the triangle.
TEST(ModelFile, OwnCutsThatDoNotFitTheNodesAreRefused) {
  const struct {
    const char* what;
    const char* expect;
    std::function<void(RawSection&)> craft;
  } cases[] = {
      {"one short", "section 'OWNC': ", [](RawSection& s) {
         s.payload.resize(s.payload.size() - 2);
         --s.count;
       }},
      {"an edge past the 12", "names edges that are not three of the node's crossed edges",
       [](RawSection& s) { s.payload[0] = 0xDC, s.payload[1] = 0x0E; }},
      {"an edge twice", "names edges that are not three of the node's crossed edges",
       [](RawSection& s) { s.payload[0] = 0x11, s.payload[1] = 0x02; }},
      {"bits past the three edges", "names edges", [](RawSection& s) { s.payload[1] |= 0x10; }},
  };
  for (const auto& c : cases) {
    std::vector<RawSection> sections = split(bunny64_bytes());
    c.craft(sections[index_of(sections, tag("OWNC"))]);
    const std::vector<std::uint8_t> bytes = join(sections, kModelFormatMajor, kModelFormatMinor);
    const std::string error = error_of(bytes.data(), bytes.size());
    EXPECT_NE(error.find("inconsistent model"), std::string::npos) << c.what << ": " << error;
    EXPECT_NE(error.find(c.expect), std::string::npos) << c.what << ": " << error;
  }
}

// (continued) A 2.x file held an octree alone, in the sections 3.0 still
// writes for it: it loads, with the octree's vertices as the model's.
TEST(ModelFile, Format2FilesOfAnOctreeStillLoad) {
  LodModel octree_only = bunny64();
  octree_only.clusters.reset();
  octree_only.cluster_vertex_first = octree_only.cluster_vertex_count = 0;
  const std::vector<std::uint8_t> current = encode_model(octree_only, 3);
  for (const std::uint32_t minor : {0u, 1u}) {
    std::vector<std::uint8_t> old = with_major(current, 2);
    set_u32(&old, 12, minor);
    set_u64(&old, 32, model_checksum(old.data(), 32));
    set_u64(&old, old.size() - 8, model_checksum(old.data(), old.size() - 8));
    ASSERT_EQ(u32_at(old, 8), 2u);
    LodModel l;
    try {
      l = decode_model(old.data(), old.size(), "old.mco");
    } catch (const InputError& e) {
      FAIL() << "a format 2." << minor << " file was refused: " << e.what();
    }
    ASSERT_TRUE(l.octree.has_value());
    EXPECT_FALSE(l.clusters.has_value());
    EXPECT_EQ(default_structure(l), LodStructure::kOctree);
    EXPECT_EQ(l.vertices.positions, octree_only.vertices.positions);
    EXPECT_EQ(l.vertices.normals, octree_only.vertices.normals);
    for (double percent : {0.0, 25.0, 100.0})
      EXPECT_EQ(extract(*l.octree, percent), extract(octree(), percent)) << percent << "%";
    // Written again, it is a 3.0 file of the same model.
    EXPECT_EQ(encode_model(l, 3), current);
  }
  // 1.x is refused even when its sections are those of a good 2.x file.
  const std::vector<std::uint8_t> one = with_major(current, 1);
  EXPECT_NE(error_of(one.data(), one.size()).find("older scan2lod"), std::string::npos) << error_of(one.data(), one.size());
}

TEST(ModelFile, ClusterHierarchyRoundTrips) {
  const LodModel& m = bunny64();
  const ClusterHierarchy& h = clusters();
  ASSERT_GT(h.levels(), 2);
  ASSERT_GT(h.groups.size(), 10u);
  EXPECT_EQ(m.cluster_vertex_first, 0u);  // it shares the octree's mesh vertices
  EXPECT_GT(m.cluster_vertex_count, 0u);
  EXPECT_LE(m.cluster_vertex_count, m.vertices.size());
  const fs::path path = scratch() / "clusters.mco";
  save_model(path.string(), m);
  const LodModel l = load_model(path.string());
  ASSERT_TRUE(l.clusters.has_value());
  EXPECT_EQ(l.cluster_vertex_first, m.cluster_vertex_first);
  EXPECT_EQ(l.cluster_vertex_count, m.cluster_vertex_count);
  EXPECT_EQ(l.clusters->clusters.size(), h.clusters.size());
  EXPECT_EQ(l.clusters->triangles, h.triangles);
  EXPECT_EQ(l.clusters->groups.size(), h.groups.size());
  EXPECT_EQ(l.clusters->full_triangles, h.full_triangles);
  EXPECT_TRUE(same_clusters(*l.clusters, h));
  EXPECT_EQ(l.clusters->levels(), h.levels());
  EXPECT_EQ(default_structure(l), LodStructure::kClusters);
  // Every kind of cluster level comes out the same.
  CameraView camera;
  const Aabb box = model_bounds(m);
  camera.target = 0.5f * (box.min + box.max);
  camera.eye = camera.target + Vec3f(0, 0, 2.5f * box.diagonal());
  for (const LevelRequest& r :
       {LevelRequest::at_percent(100), LevelRequest::at_percent(30), LevelRequest::at_percent(0),
        LevelRequest::at_error(h.groups[h.groups.size() / 2].error), LevelRequest::at_triangles(h.full_triangles / 10),
        LevelRequest::for_camera(camera, 1.0)})
    EXPECT_EQ(level(l, LodStructure::kClusters, r), level(m, LodStructure::kClusters, r)) << int(r.kind);
  EXPECT_EQ(std::int64_t(level(l, LodStructure::kClusters, LevelRequest::at_percent(100)).size()), h.full_triangles);

  // A model of the cluster hierarchy alone (build --structure clusters) round-trips too.
  LodModel alone = m;
  alone.octree.reset();
  const std::vector<std::uint8_t> bytes = encode_model(alone);
  EXPECT_EQ(u32_at(bytes, 8), kModelFormatMajor);
  const LodModel c = decode_model(bytes.data(), bytes.size(), "c.mco");
  EXPECT_FALSE(c.octree.has_value());
  ASSERT_TRUE(c.clusters.has_value());
  EXPECT_TRUE(same_clusters(*c.clusters, h));
  EXPECT_EQ(c.vertices.positions, m.vertices.positions);
  EXPECT_EQ(encode_model(c), bytes);
  // And one with neither is no model.
  LodModel none = alone;
  none.clusters.reset();
  const std::vector<std::uint8_t> empty = encode_model(none);
  EXPECT_NE(error_of(empty.data(), empty.size()).find("holds no LOD structure"), std::string::npos)
      << error_of(empty.data(), empty.size());
}

TEST(ModelFile, ClusterSectionsTruncatedOrDamagedAreNamed) {
  const std::vector<std::uint8_t>& bytes = bunny64_bytes();
  // Cut inside a section: the message names it.
  for (const char* name : {"CTRI", "CLUS", "CGRP", "CINF"}) {
    const std::uint32_t t = tag(*reinterpret_cast<const char(*)[5]>(name));
    const std::uint64_t offset = payload_offset(bytes, t), length = payload_length(bytes, t);
    ASSERT_GT(length, 1u) << name;
    for (const std::uint64_t cut : {offset + 1, offset + length / 2, offset + length - 1}) {
      const std::string error = error_of(bytes.data(), std::size_t(cut));
      EXPECT_NE(error.find("truncated in section '" + std::string(name) + "'"), std::string::npos)
          << name << " cut at " << cut << ": " << error;
    }
  }
  // A damaged byte in a cluster section: its checksum names it.
  for (const char* name : {"CGRP", "CLUS", "CTRI", "CINF"}) {
    const std::uint32_t t = tag(*reinterpret_cast<const char(*)[5]>(name));
    const std::uint64_t offset = payload_offset(bytes, t), length = payload_length(bytes, t);
    for (const std::uint64_t at : {offset, offset + length / 3, offset + length - 1}) {
      std::vector<std::uint8_t> damaged = bytes;
      damaged[std::size_t(at)] ^= 0x04;
      const std::string error = error_of(damaged.data(), damaged.size());
      EXPECT_NE(error.find("checksum mismatch in section '" + std::string(name) + "'"), std::string::npos)
          << name << " at " << at << ": " << error;
    }
  }
  // A required cluster section missing.
  std::vector<RawSection> sections = split(bytes);
  sections.erase(sections.begin() + std::ptrdiff_t(index_of(sections, tag("CTRI"))));
  const std::vector<std::uint8_t> missing = join(sections, kModelFormatMajor, kModelFormatMinor);
  EXPECT_NE(error_of(missing.data(), missing.size()).find("missing section 'CTRI'"), std::string::npos)
      << error_of(missing.data(), missing.size());
}

TEST(ModelFile, CraftedClusterHierarchiesAreRejectedBeforeExtraction) {
  // Encoded again, a crafted hierarchy has good checksums: its contents are checked.
  struct Case {
    std::string what, expect;
    std::function<void(LodModel&)> craft;
  };
  const LodModel& m = bunny64();
  const ClusterHierarchy& h = clusters();
  const std::int64_t groups = std::int64_t(h.groups.size());
  const std::size_t vertices = m.vertices.size(), range = m.cluster_vertex_count;
  // Past the mesh's vertices lie the octree's, then those the hierarchy's
  // collapses placed: its range takes all of them in.
  ASSERT_LE(range, vertices);
  // A cluster with both groups, for the error order.
  std::size_t between = 0;
  while (between < h.clusters.size() && (h.clusters[between].own_group < 0 || h.clusters[between].parent_group < 0))
    ++between;
  ASSERT_LT(between, h.clusters.size());
  const std::size_t last = h.clusters.size() - 1;
  ASSERT_GE(h.clusters[last].own_group, 0);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const std::vector<Case> cases = {
      {"a triangle range past CTRI", "triangles " + std::to_string(h.triangles.size()) + "+1 past the " +
                                         std::to_string(h.triangles.size()) + " of 'CTRI'",
       [last](LodModel& l) {
         Cluster& c = l.clusters->clusters[last];
         c.first_triangle = std::uint32_t(l.clusters->triangles.size());
         c.triangle_count = 1;
       }},
      {"a triangle range overflowing 32 bits", "past the", [last](LodModel& l) {
         l.clusters->clusters[last].first_triangle = 0xffffffffu;
         l.clusters->clusters[last].triangle_count = 2;
       }},
      {"an own group out of range", "cluster " + std::to_string(last) + ": group " + std::to_string(groups),
       [last, groups](LodModel& l) { l.clusters->clusters[last].own_group = std::int32_t(groups); }},
      {"a parent group out of range", "of " + std::to_string(groups), [groups](LodModel& l) {
         l.clusters->clusters[0].parent_group = std::int32_t(groups + 7);
       }},
      {"a group below -1", "section 'CLUS': cluster 0: group -2", [](LodModel& l) {
         l.clusters->clusters[0].own_group = -2;
       }},
      {"a triangle naming a vertex past the cluster vertices",
       "section 'CTRI': triangle 5 names vertex " + std::to_string(range) + " outside 0+" + std::to_string(range),
       [range](LodModel& l) { l.clusters->triangles[5][2] = std::int32_t(range); }},
      {"a triangle naming a negative vertex", "section 'CTRI': triangle 9 names vertex -1",
       [](LodModel& l) { l.clusters->triangles[9][0] = -1; }},
      {"a vertex range past the vertices", "lie outside the " + std::to_string(vertices) + " vertices",
       [vertices](LodModel& l) { l.cluster_vertex_count = vertices + 1; }},
      {"a non-finite group error", "section 'CGRP': group 3 needs a finite centre, radius >= 0 and error > 0",
       [nan](LodModel& l) { l.clusters->groups[3].error = nan; }},
      {"an infinite group error", "section 'CGRP': group 0 needs a finite", [inf](LodModel& l) {
         l.clusters->groups[0].error = inf;
       }},
      {"a zero group error", "group 1 needs a finite", [](LodModel& l) { l.clusters->groups[1].error = 0; }},
      {"a non-finite centre", "group 2 needs a finite", [nan](LodModel& l) { l.clusters->groups[2].center[1] = nan; }},
      {"a negative radius", "group 4 needs a finite", [](LodModel& l) { l.clusters->groups[4].radius = -1; }},
      {"a parent error below its own", "its parent group's error is below its own", [between](LodModel& l) {
         ClusterHierarchy& c = *l.clusters;
         const Cluster& cl = c.clusters[between];
         c.groups[std::size_t(cl.parent_group)].error = c.groups[std::size_t(cl.own_group)].error * 0.5f;
       }},
      {"a group that is its own parent", "its own group is its parent", [between](LodModel& l) {
         Cluster& cl = l.clusters->clusters[between];
         cl.parent_group = cl.own_group;
       }},
      {"a full-detail cluster above level 0", "level 0 and full detail", [](LodModel& l) {
         l.clusters->clusters[0].level = 1;
       }},
      {"a full-detail count CINF disagrees with", "'CINF' says", [](LodModel& l) { l.clusters->full_triangles += 1; }},
      {"no clusters", "has no clusters", [](LodModel& l) { l.clusters->clusters.clear(); }},
  };
  for (const Case& c : cases) {
    LodModel crafted = m;
    c.craft(crafted);
    const std::vector<std::uint8_t> bytes = encode_model(crafted);
    const std::string error = error_of(bytes.data(), bytes.size());
    EXPECT_EQ(error.rfind("m.mco: ", 0), 0u) << c.what << ": " << error;
    EXPECT_NE(error.find("inconsistent model"), std::string::npos) << c.what << ": " << error;
    EXPECT_NE(error.find(c.expect), std::string::npos) << c.what << ": " << error;
  }
  // A CINF record of another size.
  std::vector<RawSection> sections = split(bunny64_bytes());
  RawSection& info = sections[index_of(sections, tag("CINF"))];
  info.payload.resize(16);
  info.element_size = 16;
  const std::vector<std::uint8_t> short_info = join(sections, kModelFormatMajor, kModelFormatMinor);
  EXPECT_NE(error_of(short_info.data(), short_info.size()).find("section 'CINF' must be one record of 24 bytes"),
            std::string::npos)
      << error_of(short_info.data(), short_info.size());
  // CLUS records of another size.
  sections = split(bunny64_bytes());
  RawSection& clus = sections[index_of(sections, tag("CLUS"))];
  clus.element_size = 8;
  clus.count *= 2;
  const std::vector<std::uint8_t> narrow = join(sections, kModelFormatMajor, kModelFormatMinor);
  EXPECT_NE(error_of(narrow.data(), narrow.size()).find("section 'CLUS' has elements of 8 bytes, expected 16"),
            std::string::npos)
      << error_of(narrow.data(), narrow.size());
}

// A model of georeferenced inputs keeps the point of their frame its
// vertices are relative to (4.5, ORGN), bit for bit; a model without one
// writes the bytes it wrote before (no ORGN), and a 4.4 file reads as zero.
TEST(ModelFile, TheInputsOriginRoundTripsAndIsWrittenOnlyWhenSet) {
  LodModel m = bunny64();
  EXPECT_EQ(m.origin, Vec3d::Zero());
  const std::vector<RawSection> plain = split(bunny64_bytes());
  for (const RawSection& s : plain) EXPECT_NE(s.tag, tag("ORGN"));

  m.origin = Vec3d(500123.456, 5001234.5678901, 301.25);  // UTM east, north, height
  const std::vector<std::uint8_t> bytes = encode_model(m);
  std::vector<RawSection> sections = split(bytes);
  ASSERT_EQ(sections.size(), plain.size() + 1);
  const RawSection& orgn = sections[index_of(sections, tag("ORGN"))];
  EXPECT_EQ(orgn.flags, 0u) << "optional: a 4.4 reader skips it";
  EXPECT_EQ(orgn.element_size, 24u);
  EXPECT_EQ(orgn.count, 1u);
  const LodModel l = decode_model(bytes.data(), bytes.size(), "utm.mco");
  EXPECT_EQ(l.origin, m.origin);  // every bit of the doubles
  EXPECT_EQ(l.vertices.positions, m.vertices.positions);
  EXPECT_EQ(level(l, LodStructure::kClusters, LevelRequest::at_percent(25)),
            level(m, LodStructure::kClusters, LevelRequest::at_percent(25)));
  // Without it (a 4.4 writer) the origin is zero; the rest is the same model.
  sections.erase(sections.begin() + std::ptrdiff_t(index_of(sections, tag("ORGN"))));
  const std::vector<std::uint8_t> old = join(sections, kModelFormatMajor, 4);
  EXPECT_EQ(decode_model(old.data(), old.size(), "old.mco").origin, Vec3d::Zero());
  // A crafted origin is refused by name.
  sections = split(bytes);
  RawSection& crafted = sections[index_of(sections, tag("ORGN"))];
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::memcpy(crafted.payload.data() + 8, &nan, 8);
  std::vector<std::uint8_t> bad = join(sections, kModelFormatMajor, kModelFormatMinor);
  EXPECT_NE(error_of(bad.data(), bad.size()).find("section 'ORGN': the origin must be a finite point"),
            std::string::npos)
      << error_of(bad.data(), bad.size());
  crafted.payload.resize(16);
  crafted.element_size = 16;
  bad = join(sections, kModelFormatMajor, kModelFormatMinor);
  EXPECT_NE(error_of(bad.data(), bad.size()).find("section 'ORGN' must be one record of 24 bytes"),
            std::string::npos)
      << error_of(bad.data(), bad.size());
}

TEST(ModelFile, Format5IsRefusedAsNewer) {
  static_assert(kModelFormatMajor == 4, "this reader writes format 4");
  const std::vector<std::uint8_t> five = with_major(bunny64_bytes(), 5);
  const std::string error = error_of(five.data(), five.size());
  EXPECT_NE(error.find("newer"), std::string::npos) << error;
  EXPECT_NE(error.find("format 5." + std::to_string(kModelFormatMinor)), std::string::npos) << error;
  EXPECT_NE(error.find("reads up to 4"), std::string::npos) << error;
  // Before anything past the header is looked at.
  EXPECT_NE(error_of(five.data(), 40).find("newer"), std::string::npos);
}

// Format 4 packs the octree (lod/octree/model_pack.h) and derives the rest at load
// time: the same model as format 3 holds, in under a third of the bytes.
TEST(ModelFile, Format4PacksTheOctreeAndHoldsTheSameModelAsFormat3) {
  const std::vector<std::uint8_t> three = encode_model(bunny64(), 3);
  const std::vector<std::uint8_t>& four = bunny64_bytes();
  EXPECT_EQ(u32_at(three, 8), 3u);
  EXPECT_EQ(u32_at(four, 8), 4u);
  // Either file read and written again in the other format gives that format's bytes.
  EXPECT_EQ(encode_model(decode_model(three.data(), three.size(), "three.mco")), four);
  EXPECT_EQ(encode_model(decode_model(four.data(), four.size(), "four.mco"), 3), three);
  // The octree's sections (all but the shared vertices and the clusters').
  auto octree_bytes = [](const std::vector<std::uint8_t>& b) {
    std::uint64_t total = 0;
    for (const RawSection& s : split(b))
      if (s.tag != tag("POSN") && s.tag != tag("NRML") && s.tag != tag("COLR") && s.tag != tag("CINF") &&
          s.tag != tag("CLUS") && s.tag != tag("CTRI") && s.tag != tag("CGRP") && s.tag != tag("PAGE") &&
          s.tag != tag("PGIX") && s.tag != tag("PGEO"))
        total += s.payload.size();
    return total;
  };
  EXPECT_LT(3 * octree_bytes(four), octree_bytes(three)) << octree_bytes(four) << " against " << octree_bytes(three);
  for (const char* gone : {"KEYS", "LEVL", "PRNT", "FCHD", "NCHD", "EDGV", "FTRI", "NTRI", "SUBV", "NBRS", "TRIS"})
    for (const RawSection& s : split(four)) EXPECT_NE(s.tag, tag(*reinterpret_cast<const char(*)[5]>(gone))) << gone;
}

TEST(ModelFile, CraftedPackedSectionsAreRejectedBeforeExtraction) {
  struct Case {
    const char* what;
    const char* section;
    std::string expect;
    std::function<void(RawSection&)> craft;
  };
  const std::vector<Case> cases = {
      {"an edge vertex missing", "EDGP", "holds fewer vertices than 'EDGM' names",
       [](RawSection& s) { s.payload.resize(s.payload.size() - 4), --s.count; }},
      {"an edge vertex too many", "EDGP", "'EDGM' names",
       [](RawSection& s) { s.payload.insert(s.payload.end(), 4, 0), ++s.count; }},
      {"an edge mask past 12 edges", "EDGM", "names an edge past 12", [](RawSection& s) { s.payload[1] |= 0x80; }},
      {"a sub-edge vertex missing", "SUBP", "holds fewer vertices than 'SUBM' names",
       [](RawSection& s) { s.payload.resize(s.payload.size() - 4), --s.count; }},
      {"a leaf with children", "CHLD", "section 'CHLD'", [](RawSection& s) { s.payload.back() = 1; }},
      {"a node that is no node's child", "CHLD", "section 'CHLD'", [](RawSection& s) { s.payload[0] = 0; }},
      {"a triangle its case lacks", "TMSK", "names a triangle its case lacks", [](RawSection& s) {
         for (std::uint8_t& m : s.payload) m = 0xff;
       }},
      {"a case array one short", "CASE", "'CASE' has", [](RawSection& s) { s.payload.pop_back(), --s.count; }},
  };
  for (const Case& c : cases) {
    std::vector<RawSection> sections = split(bunny64_bytes());
    c.craft(sections[index_of(sections, tag(*reinterpret_cast<const char(*)[5]>(c.section)))]);
    const std::vector<std::uint8_t> bytes = join(sections, kModelFormatMajor, kModelFormatMinor);
    const std::string error = error_of(bytes.data(), bytes.size());
    EXPECT_NE(error.find("inconsistent model"), std::string::npos) << c.what << ": " << error;
    EXPECT_NE(error.find(c.expect), std::string::npos) << c.what << ": " << error;
  }
}
