#include <scan2lod/distributed/work_sharing.h>

#include <scan2lod/core/error.h>
#include <scan2lod/distributed/mpi_work_sharing.h>

#include <cstdlib>
#include <string>

namespace scan2lod {
namespace {

// One process: every index runs here, in order.
class SerialWorkSharing final : public WorkSharing {
 public:
  int rank() const override { return 0; }
  int ranks() const override { return 1; }
  void share(std::size_t count, const std::function<void(std::size_t)>& work,
             const std::function<void(std::size_t)>& finished) override {
    for (std::size_t i = 0; i < count; ++i) {
      work(i);
      if (finished) finished(i);
    }
  }
  std::vector<std::string> gather_all(const std::string& mine) override { return {mine}; }
  void broadcast(std::string*) override {}
  void broadcast_from(int, void*, std::size_t) override {}
  [[noreturn]] void abort(int exit_code) override { std::exit(exit_code); }
};

}  // namespace

std::unique_ptr<WorkSharing> serial_work_sharing() { return std::make_unique<SerialWorkSharing>(); }

bool launched_by_mpi() {
  // OpenMPI's mpirun, MPICH's Hydra (PMI), and PMIx launchers such as srun.
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(name)) return true;
  return false;
}

std::unique_ptr<WorkSharing> join_job() {
  if (!launched_by_mpi()) return serial_work_sharing();
  if (std::unique_ptr<WorkSharing> job = join_mpi_job()) return job;
  // Without MPI each process of the job would build alone, all into one
  // work folder and output.
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
    if (const char* size = std::getenv(name); size && std::atoi(size) > 1)
      throw InputError("", "started by an MPI launcher as " + std::string(size) +
                               " processes, but this scan2lod was built without MPI: run it as one process, "
                               "or build it with MPI (libopenmpi-dev)");
  return serial_work_sharing();
}

}  // namespace scan2lod
