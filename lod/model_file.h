// The LOD model on disk (`.mco`): a prioritized marching-cube octree with its
// LOD array and accumulation table (Lee 2007, §6.1), so that a mesh of any size
// is taken from a file without rebuilding anything.
//
// Layout (every number little-endian; checksums are XXH64, seed 0):
//
//   header, 40 bytes
//     0  char[8] magic "SCAN2LOD"
//     8  u32     major format version (a reader rejects majors it does not know)
//    12  u32     minor format version (new optional sections only)
//    16  u32     section count S
//    20  u32     flags, 0
//    24  u64     file length in bytes, trailer included
//    32  u64     checksum of bytes 0..31
//   directory, S entries of 48 bytes, then a u64 checksum of the entries
//     0  u32 tag (fourcc: 'K','E','Y','S' is "KEYS")
//     4  u32 flags: bit 0 = required (a reader that does not know the tag must
//            reject the file; unknown sections without it are skipped)
//     8  u32 element size in bytes
//    12  u32 reserved, 0
//    16  u64 element count
//    24  u64 payload offset from the start of the file (a multiple of 8)
//    32  u64 payload length = element size * element count
//    40  u64 checksum of the payload
//   payloads, each zero-padded to 8 bytes
//   trailer: u64 checksum of every byte before it
//
// Bytes 0..15 and 32..39 keep their meaning in every future version, so any
// reader can tell a damaged file from a newer one. Sections of format 1.0, all
// required (count n = nodes unless said otherwise):
//   GRID  1 record of 48 bytes: f64 origin[3], f64 cube size, i32 resolution,
//         i32 depth, u64 mesh_vertices (a longer record from a newer minor
//         version is read by its first 48 bytes)
//   KEYS u64, LEVL u8, PRNT i32, FCHD i32, NCHD u8, CASE u8, EDGV i32[12],
//   FTRI i32, NTRI u8, METR f32           McOctree's per-node arrays
//   BINS u32, SUBV i32[48], CNTR i32,
//   NBRS i32[27]                           crack patching, per internal node
//   TRIS i32[3], PTRI i32[3]               triangles, patch_triangles
//   PGRP i32, PNDF i32, PNDS i32           patch_group_first, patch_needs_first, patch_needs
//   POSN f32[3], NRML f32[3], COLR u8[3]   vertices (NRML, COLR: 0 or POSN's count)
//   LODO i32, LODA i64                     LodArray::order, ::accumulated
// Added in 1.1, optional (a 1.0 reader skips it and may offer levels inside the
// pinned prefix; a 1.1 reader of a 1.0 file takes 0):
//   PINC u64, one                          LodArray::pinned
// Format 2.0 has 1.1's sections; what changed is how extraction triangulates a
// transition with several loops (one loop around the centre, lod/octree/transition.h),
// so a 1.x file's accumulation table no longer counts what extraction emits
// and a reader rejects it.
// Format 3.0 holds one or both LOD structures over one shared vertex array
// (lod/lod_model.h): POSN, NRML and COLR always; the octree's sections above
// when the model has an octree (GRID marks it); and the cluster hierarchy's
// when it has one (CINF marks it), all required:
//   CINF  1 record of 24 bytes: u64 full-detail triangles, u64 first vertex,
//         u64 vertex count (the range of the shared vertices it indexes)
//   CLUS  Cluster records of 16 bytes: u32 first triangle, u16 triangle count,
//         u8 DAG level, u8 0, i32 own group, i32 parent group (-1: none)
//   CTRI  i32[3] triangles, cluster by cluster
//   CGRP  GroupBound records of 20 bytes: f32 centre[3], radius, error
// A 2.x file (an octree alone) still loads.
// Format 4.0 packs the octree (lod/octree/model_pack.h) and derives at load time what
// is cheap to derive; a 3.x file still loads, and 4.0 writes the same model.
// KEYS, LEVL, PRNT, FCHD, NCHD, EDGV, FTRI, NTRI, SUBV, NBRS and TRIS are gone;
// in their place, all required:
//   CHLD u8 per node           child mask (bit o: the child in octant x + 2y + 4z),
//                              nodes breadth-first, children by octant
//   EDGM u16 per node, EDGP i32  which of the 12 edges hold a vertex, and those
//                              vertices, node by node
//   TMSK u8 per node           which of its case's triangles the node has
//                              (triangles laid out from the leaves' level up)
//   SUBM u64 per internal node, SUBP i32  the same for the 48 sub-edges
// Neighbours are found again from the tree. On the bunny at R = 256 the file
// went from 58.3 to 18.4 MB (the octree's part from 51.4 to 11.4 MB).
// Added in 4.1, optional (a 4.0 reader skips it and offers levels inside the
// coarsening's steps, lod/octree/coarsening.h, which may be unsound; a 4.1 reader of
// an older file offers every level past the pinned prefix):
//   STEP i32, ascending        LodArray::inside_steps, priority numbers not offered
// Added in 4.2, optional (a 4.1 reader skips it and may fan a transition loop
// into a triangle of no area where a flat surface meets a node face in line,
// lod/octree/transition.h; a 4.2 reader of an older file takes all zero, as that
// file's LODA was counted):
//   STRF u8 per internal node  OctreeTransitions::straight_faces
// Added in 4.3, optional (a 4.2 reader skips it and cuts the internal nodes'
// polygons along the case table's diagonals: the same outlines, so the same
// topology, a little farther from the surface; a 4.3 reader of an older file
// does the same):
//   OWNC u16 per triangle of the internal nodes, laid out as their triangles
//                              the three edges whose vertices the triangle
//                              joins, 4 bits each (lod/octree/model_pack.h)
// Added in 4.4, optional (a 4.3 reader skips it; a 4.4 reader of an older
// file derives the pages, lod/clusters/cluster_hierarchy.h):
//   PAGE  ClusterPage records of 32 bytes: u32 first cluster, u32 cluster
//         count, f32 centre[3], radius, min error, max error: runs of
//         clusters whose triangles are one run of CTRI (64 KiB at most unless
//         one cluster is larger), so that a viewer reads only the pages whose
//         sphere it sees and whose error interval holds its threshold
// Added in 4.5, optional, written only when the origin is not zero (a 4.4
// reader skips it and gives levels about the origin, i.e. shifted out of the
// inputs' frame; a 4.5 reader of an older file takes zero):
//   ORGN  1 record of 24 bytes: f64 origin[3], LodModel::origin, the point of
//         the inputs' frame that the vertices are relative to (georeferenced
//         inputs: input frame = origin + POSN, added in double)
// Added in 4.6, optional, written when the hierarchy's pages lie in the order
// of CTRI (a 4.5 reader, and load_model, skip them; a paged reader of an
// older file reads it whole):
//   PGIX  PageExtent records of 48 bytes, one a page (lod/clusters/page_geometry.h):
//         where its geometry lies in PGEO, its checksum and box
//   PGEO  bytes: each page's triangles over a vertex table of its own
//         (lod/clusters/page_geometry.h), so that a viewer reads a page in one read
// Added in 4.7, optional (a 4.6 reader ranks cuts by count with the errors):
//   CGRK  f32 per group: the rank cuts by triangle count go by
//         (ClusterHierarchy::group_ranks)
// Every section is listed once, with the formats that hold it: the shared
// vertices' in model_file.cpp, each structure's in its part
// (lod/model_sections.h: lod/octree/octree_sections.cpp,
// lod/clusters/cluster_sections.cpp). The writer and the reader both walk those
// tables, structure by structure. A new array is a new row there (and, if it
// must agree with others, a check in that part's decode). When older readers can still draw the model without it, the
// writer marks it optional and bumps the minor version; otherwise it is
// required and the major version goes up.
#pragma once

#include <scan2lod/lod/clusters/page_geometry.h>
#include <scan2lod/lod/lod_model.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace scan2lod {

constexpr std::uint32_t kModelFormatMajor = 4;
constexpr std::uint32_t kModelFormatMinor = 7;

// Writes `model` to `path` (extension .mco) through write_atomically: a
// failure or a signal leaves nothing under `path`.
// Throws InputError for another extension, a missing folder or a failed write.
void save_model(const std::string& path, const LodModel& model);

// Reads and validates a model written by save_model. Throws InputError naming
// the file and what is wrong: not a model (bad magic), truncated (naming the
// section), a checksum mismatch (naming the section), a newer major format,
// or contents that disagree (array lengths against the node count, child,
// parent, triangle, vertex, neighbour or LOD indices out of range, a sign
// change on a node's boundary without a vertex), so that extract_lod and
// compact_lod cannot read out of bounds on a loaded model. Peak memory is
// about twice the file's size, whatever its counts claim.
LodModel load_model(const std::string& path);

// The bytes save_model writes (held in memory whole), and their reading
// (`source` names them in errors); load_model is read-the-file plus decode_model.
// `major` 3 writes the 3.0 layout, which this reader still loads (the tests
// use it for files whose arrays the packed layout cannot express); any other
// but the current throws std::invalid_argument.
std::vector<std::uint8_t> encode_model(const LodModel& model, std::uint32_t major = kModelFormatMajor);
LodModel decode_model(const std::uint8_t* data, std::size_t size, const std::string& source);

// What reading a model page by page (lod/clusters/paged_model.h) starts from, read
// without the vertices, the triangles or the octree: the origin, the cluster
// hierarchy's clusters, groups and pages (its triangles left empty), and
// where each page's geometry lies in the file.
struct ModelPagesHead {
  LodModel model;                   // no model.clusters: the file has no pages to read
  std::vector<PageExtent> extents;  // one a page
  std::uint64_t pages_offset = 0;   // where section 'PGEO' starts in the file
  std::uint64_t vertices = 0;       // the model's shared vertices, which pages name
  bool normals = false, colors = false;
  std::uint64_t bytes_read = 0;     // to read this far
};

// Reads that much of `path`, checking what it reads as load_model does (the
// sections' checksums, and that the hierarchy's arrays agree). Files with no
// cluster hierarchy, or with no pages of geometry (written before format 4.6),
// give no model.clusters. Throws InputError naming the file.
ModelPagesHead read_model_pages_head(const std::string& path);

// Throws InputError unless save_model could write `path`: extension .mco
// (any case) in an existing folder. Commands call it before long work.
void check_model_output(const std::string& path);

// XXH64 (Yann Collet's xxHash, 64-bit) of `size` bytes: the file's checksum.
std::uint64_t model_checksum(const void* data, std::size_t size, std::uint64_t seed = 0);

}  // namespace scan2lod
