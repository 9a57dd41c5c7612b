// Work shared by the processes of one job. A build started as
// `mpirun -np N scan2lod build ...` runs N processes (ranks); the bricks of
// its reconstruction are independent work, handed out to whichever rank asks
// next; each rank reads a share of the inputs, and rank 0 does everything
// else (welding, the LOD structures, writing the model). The ranks meet
// only through this face and through the work folder, which they must all
// see at the same path: a shared file system when they run on more than one
// machine.
//
// Two implementations stand behind it: this process alone (serial_work_sharing),
// and MPI (join_job(), when scan2lod was built with MPI and launched by an MPI
// launcher). Code that shares work calls the face and never MPI, so that a
// build without MPI has the same code path as a one-rank job.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace scan2lod {

class WorkSharing {
 public:
  virtual ~WorkSharing() = default;
  virtual int rank() const = 0;   // 0 is the rank that writes the output
  virtual int ranks() const = 0;  // N

  // Collective: every rank calls it with the same count. Calls work(i) on
  // this rank for the indices of [0, count) it claims; every index runs on
  // exactly one rank, handed out in ascending order to the rank that asks
  // next (dynamic scheduling: items may differ a lot in cost). `finished(i)`
  // is called on rank 0 only, once per index when its work ended on any rank
  // (for progress), from any thread, never two at once. Returns once every
  // index is done everywhere. An exception from work() propagates on its rank
  // only: the caller ends the job (abort()), or the other ranks wait forever.
  virtual void share(std::size_t count, const std::function<void(std::size_t)>& work,
                     const std::function<void(std::size_t)>& finished) = 0;

  // Collective: every rank's bytes, in rank order, on every rank.
  virtual std::vector<std::string> gather_all(const std::string& mine) = 0;

  // Collective: rank 0's *bytes on every rank (read on rank 0, replaced on
  // the others).
  virtual void broadcast(std::string* bytes) = 0;

  // Collective: rank `root`'s `size` bytes at `data` on every rank, written
  // over the others' `data` (which every rank has sized alike). For arrays
  // too large to copy into a message first (a mesh's vertices).
  virtual void broadcast_from(int root, void* data, std::size_t size) = 0;

  // Ends every rank of the job with `exit_code`. The caller has printed why.
  [[noreturn]] virtual void abort(int exit_code) = 0;
};

// This process alone: rank 0 of 1.
std::unique_ptr<WorkSharing> serial_work_sharing();

// The job this process belongs to: an MPI job when scan2lod was built with
// MPI and an MPI launcher (mpirun, mpiexec, srun with PMIx) started it, else
// this process alone. MPI is initialised here and finalised when the returned
// object is destroyed, so call it once per process. Throws InputError when a
// launcher started several processes and scan2lod was built without MPI.
std::unique_ptr<WorkSharing> join_job();

// Whether an MPI launcher started this process (from its environment),
// whether or not scan2lod was built with MPI.
bool launched_by_mpi();

}  // namespace scan2lod
