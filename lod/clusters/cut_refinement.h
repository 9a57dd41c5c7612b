// A cut by triangle count, refined to the count by edge collapse.
//
// The hierarchy's levels lie about a halving apart, and near full detail the
// error grows fast between them (7x from the first level to the second on
// the pair's scans at R = 256, for VTK's QuadricDecimation as for us). A
// count between two levels gets a mix of both, whose error is the mix of
// theirs: 1.4x what a simplifier going to that count directly reaches. So a
// count is served from a finer stored cut, at most kRefineHeadroom times the
// count, collapsed the rest of the way as one mesh with nothing locked.
// The collapses are half-edge ones (each edge onto one of its ends), so the
// refined cut is still an index buffer into the model's vertices, as every
// cut is (extraction by reference); where the stored cuts are too far apart
// (the coarse end), the stored cut serves as it is, unless it would miss
// the count by more than 10 %.
#pragma once

#include <scan2lod/lod/clusters/cluster_cut.h>
#include <scan2lod/lod/lod_model.h>

#include <cstdint>
#include <vector>

namespace scan2lod {

class ClusterPages;  // lod/clusters/paged_model.h

// How much finer than the count the cut refined may be. Measured on the
// pair's scans at R = 256, at 100 k of 196 k triangles, against VTK's
// QuadricDecimation (scan2lod_bench_lod --only Decimation, one build per
// value): 1.16x its error from 1.12, 1.07x from 1.25, 1.11x from 1.4,
// 1.17x from 1.6.
constexpr double kRefineHeadroom = 1.25;

// The largest stored cut refined: about 600 bytes and 3.5 us a triangle
// (a cut of 2.86 M triangles took 10 s and 1.6 GB), so at most about
// 650 MB and 4 s; larger counts get the stored cut. Blocks with locked
// borders, as the build's, would lift this; not done.
constexpr std::int64_t kRefineMostTriangles = std::int64_t(1) << 20;

// The rank of the stored cut that `budget` triangles are refined from: the
// finest uniform cut of at most kRefineHeadroom x budget, when it has more
// than the budget; where none has and the cut under the budget falls more
// than 10 % short of it (a gap between the stored cuts, on high-genus scans
// at the coarse end), the coarsest cut above; in both cases at most
// kRefineMostTriangles. -1 otherwise: a stored cut serves as it is.
float rank_to_refine(const ClusterCutTable& table, std::int64_t budget);

// Collapses a cut to at most `target` triangles. Scratch space is kept
// between calls.
class CutRefiner {
 public:
  struct Result {
    bool refined = false;  // false: the cut stays as it was (no collapse was allowed)
    float error = 0;       // the largest deviation of a vertex collapsed, in the model's units
  };
  // What the cut's triangles index.
  struct Vertices {
    ArrayView<Vec3f> positions;
    ArrayView<Vec3f> normals;  // empty or one per position
    ArrayView<Rgb> colors;     // empty or one per position
  };
  // In `kept`, per triangle left, which it was.
  Result refine(const Vertices& vertices, std::vector<Triangle>* triangles, std::size_t target,
                std::vector<std::uint32_t>* kept);
  // The same for a cut of a model read page by page (the last `pages`
  // emitted): over the pages' vertices, numbered in the model's order so
  // that the collapses, which break ties by vertex order, are the whole
  // model's; `triangles` stay in the model's numbering.
  Result refine_pages(const ClusterPages& pages, std::vector<Triangle>* triangles, std::size_t target,
                      std::vector<std::uint32_t>* kept);

 private:
  std::vector<std::int32_t> used_, weld_;
  std::vector<Vec3f> points_;
  std::vector<Triangle> welded_;
  std::vector<std::uint32_t> whole_;  // welded_[i] was triangle whole_[i]
};

}  // namespace scan2lod
