// Built when CMake found no MPI: every job is this process alone.
#include <scan2lod/distributed/mpi_work_sharing.h>

namespace scan2lod {

std::unique_ptr<WorkSharing> join_mpi_job() { return nullptr; }

}  // namespace scan2lod
