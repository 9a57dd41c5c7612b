// An exact kd-tree over oriented points' positions (FLANN's
// KDTreeSingleIndex), below its users: cloud normals (acquisition/), signed
// distances (reconstruct/) and the octree's corner signs (lod/).
#pragma once

#include <scan2lod/core/types.h>

#include <cstddef>
#include <cstdint>
#include <memory>

namespace scan2lod {

class PointIndex {
 public:
  // Throws InputError when `points` is empty.
  explicit PointIndex(const OrientedPoints& points);
  ~PointIndex();
  PointIndex(const PointIndex&) = delete;
  PointIndex& operator=(const PointIndex&) = delete;

  // For each query, the k nearest points (indices, squared distances), row-major
  // count x k; equal distances in index order, and a tie at the k-th broken by
  // index, so that any subset that holds them (a brick) gives the same
  // neighbours in the same order. Runs on `threads` threads (0: all).
  void knn(const Vec3f* queries, std::size_t count, int k, std::int32_t* indices,
           float* squared_distances, int threads) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace scan2lod
