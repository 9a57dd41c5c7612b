// The MPI implementation of WorkSharing (internal to distributed/): built
// from mpi_work_sharing.cpp when CMake found MPI, else from no_mpi.cpp.
#pragma once

#include <scan2lod/distributed/work_sharing.h>

#include <memory>

namespace scan2lod {

// Initialises MPI and returns this process's place in MPI_COMM_WORLD; null
// when scan2lod was built without MPI.
std::unique_ptr<WorkSharing> join_mpi_job();

}  // namespace scan2lod
