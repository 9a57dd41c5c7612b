// Reconstruction brick by brick, for surfaces whose marching cubes do not fit
// in memory at once. The grid is the one reconstruct() uses; it is cut into
// bricks of B^3 cubes, and each brick is followed and emitted from its own
// points plus a halo of neighbours wide enough that every signed distance it
// needs is the one the whole point set gives. Bricks hand each other the cubes
// their surface leads into until none is left, so the followed set is the
// whole grid's. Vertices are keyed by their lattice edge, so the bricks' shares
// weld exactly; small pieces are then dropped on the welded whole.
//
// Finished bricks are kept in a work folder, written atomically, so a build
// that is killed resumes from them and ends with the same surface.
//
// The bricks of one pass are independent work: under MPI (BrickOptions::
// sharing) they are handed out to the ranks of the job as each asks for the
// next, and the ranks tell each other after every pass what their bricks
// asked of their neighbours. Each rank reads a share of the input files;
// rank 0 bins the points and welds, or (when the points are larger than a
// quarter of the budget) every rank bins the share it read and rank 0 welds.
// The other ranks take part through serve_bricks(). Every brick is the one a
// single process computes, so the surface is the same whatever the ranks.
#pragma once

#include <scan2lod/reconstruct/marching_cubes.h>
#include <scan2lod/reconstruct/point_spool.h>

#include <functional>
#include <string>

namespace scan2lod {

class WorkSharing;

struct BrickOptions {
  std::string work_dir;      // finished bricks are kept here; created if missing
  double memory_bytes = 0;   // one brick's work must fit; 0: the machine's
  int brick_cubes = 0;       // cubes per brick side (a power of two); 0: from memory_bytes
  // Called once the points are binned on disk: from there on the build reads
  // them from the bins only, so a caller may free its own copy.
  std::function<void()> points_binned;
  // The ranks that share the bricks (this one is rank 0 of them: the one that
  // holds the points and welds), all seeing work_dir at the same path; null:
  // this process alone.
  WorkSharing* sharing = nullptr;
};

struct BrickPlan {
  CubeGrid grid;
  int brick_cubes = 0;       // B
  int bricks_per_axis = 0;   // ceil(R / B)
  double halo = 0;           // world units of neighbours around a brick, at least (bricks near
                             // points of wide spacing get more: their influence reaches farther)
  double cubes = 0;          // cubes the whole surface is expected to touch (estimate_reconstruction)
  double brick_bytes = 0;    // estimated peak of the largest brick
  double weld_bytes = 0;     // estimated peak of welding the surface
  double disk_bytes = 0;     // estimated size of the finished bricks and the binned points
  double estimated_bytes = 0;  // the in-core reconstruction's estimate (estimate_reconstruction)
  double median_spacing = 0; // of the points with spacing (sampled past 2^20 points); 0 without
  std::uint64_t key = 0;     // hash of the points and options: a brick of another plan is never reused
};

// The bricks for `points` at options.resolution within options' memory.
// Throws InputError when not even the smallest brick (4 halos wide) fits,
// naming the memory it needs.
BrickPlan plan_bricks(const OrientedPoints& points, const ReconstructOptions& options, const BrickOptions& bricks);
// The same for points spooled to disk (closed), read in passes. For one share
// of a job's points (PointSpool::join) every rank of bricks.sharing calls it,
// with its own share, and all get the same plan.
BrickPlan plan_bricks(const PointSpool& points, const ReconstructOptions& options, const BrickOptions& bricks);

struct BrickStats {
  std::size_t bricks = 0;          // bricks with points
  std::size_t brick_runs = 0;      // runs, with the reruns that requests and wider halos caused
  std::size_t bricks_resumed = 0;  // taken from the work folder as they were
  std::size_t follow_passes = 0;   // passes until no brick asked another for a cube
  double widest_halo = 0;          // world units: near points of wide spacing a halo grows
};

// The surface of reconstruct(points, options), built brick by brick. Same
// triangles and positions as in core when options.max_hole is 0; with hole
// closing, holes are closed by rim triangles only (fill_small_holes), not by
// marching on into cubes. `leaves` stays empty: the octree needs the in-core
// build.
// `plan`: plan_bricks(points, options, bricks), when the caller made it already.
Reconstruction reconstruct_in_bricks(const OrientedPoints& points, const ReconstructOptions& options,
                                     const BrickOptions& bricks, BrickStats* stats = nullptr,
                                     const BrickPlan* plan = nullptr);
// The same for points spooled to disk: what the build holds of them at once
// is one brick's with its halo, whatever their number. For one share of a
// job's points, rank 0's call, while the others serve_bricks(share, ...).
Reconstruction reconstruct_in_bricks(const PointSpool& points, const ReconstructOptions& options,
                                     const BrickOptions& bricks, BrickStats* stats = nullptr,
                                     const BrickPlan* plan = nullptr);

// On a rank other than 0 of bricks.sharing: waits for rank 0's plan, runs
// the bricks it is handed out (reading the points rank 0 binned in
// bricks.work_dir), and returns when every pass is over; or at once, when
// rank 0 builds without bricks (release_brick_workers). `options` must be
// rank 0's (a plan made with other options is refused).
void serve_bricks(const ReconstructOptions& options, const BrickOptions& bricks);

// On a rank other than 0, when every rank spooled a share of the points
// (PointSpool::join): plans with the others, bins its share, and runs the
// bricks it is handed out, while rank 0 runs reconstruct_in_bricks() on its
// own share. `options` and `bricks` must be rank 0's.
void serve_bricks(const PointSpool& share, const ReconstructOptions& options, const BrickOptions& bricks);

// On rank 0: tells the ranks waiting in serve_bricks() that no bricks come.
// Call it instead of reconstruct_in_bricks() when a build shares its work;
// nothing when `sharing` is null or alone.
void release_brick_workers(WorkSharing* sharing);

}  // namespace scan2lod
