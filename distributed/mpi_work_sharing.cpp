// WorkSharing over MPI. Bricks are handed out by rank 0: a thread of rank 0
// answers the other ranks' requests for the next index while its main
// thread works through the same sequence, so rank 0 works too. Waits poll
// and sleep instead of MPI's blocking calls, which spin: a rank that waits
// must leave its core to the ranks that work beside it (two ranks on two
// cores, or more ranks than cores).
#include <scan2lod/distributed/mpi_work_sharing.h>

// The C API only: mpi.h would otherwise pull in MPI's old C++ bindings,
// which need a library the C target does not link.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>

#include <atomic>
#include <chrono>
#include <climits>
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace scan2lod {
namespace {

constexpr int kAsk = 1;   // rank -> 0: the index it finished (or kNone), asking for the next
constexpr int kGive = 2;  // 0 -> rank: the next index, or kNone when all are handed out
constexpr std::uint64_t kNone = ~std::uint64_t(0);
// Messages are cut into pieces MPI's int counts can hold.
constexpr std::size_t kPiece = std::size_t(1) << 30;

void pause_briefly() { std::this_thread::sleep_for(std::chrono::microseconds(500)); }

// Waits for a request without spinning for long.
void wait(MPI_Request* request) {
  for (int polls = 0;; ++polls) {
    int done = 0;
    MPI_Test(request, &done, MPI_STATUS_IGNORE);
    if (done) return;
    if (polls >= 64) pause_briefly();
  }
}

class MpiWorkSharing final : public WorkSharing {
 public:
  MpiWorkSharing() {
    // The ranks exchange kilobytes (brick ids, the cubes bricks ask of each
    // other); points and bricks go through the shared work folder. OpenMPI's
    // UCX layer raised rank 0's peak by 30 to 60 MiB over the same build
    // alone (1 M points, R = 1024, --memory 400M: 424 to 460 MiB against 384
    // to 393), past what the budget allows; its own point-to-point layer (ob1)
    // costs a few MiB. A layer the user chose (mpirun --mca pml ...) stays.
    ::setenv("OMPI_MCA_pml", "ob1", 0);
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_MULTIPLE, &provided);
    // Rank 0 serves from a thread while its main thread works (and makes no
    // MPI call meanwhile): serialized calls are enough.
    serve_from_thread_ = provided >= MPI_THREAD_SERIALIZED;
    MPI_Comm_dup(MPI_COMM_WORLD, &comm_);
    MPI_Comm_rank(comm_, &rank_);
    MPI_Comm_size(comm_, &ranks_);
  }
  ~MpiWorkSharing() override {
    MPI_Comm_free(&comm_);
    MPI_Finalize();
  }
  MpiWorkSharing(const MpiWorkSharing&) = delete;
  MpiWorkSharing& operator=(const MpiWorkSharing&) = delete;

  int rank() const override { return rank_; }
  int ranks() const override { return ranks_; }

  void share(std::size_t count, const std::function<void(std::size_t)>& work,
             const std::function<void(std::size_t)>& finished) override {
    if (ranks_ == 1) {
      for (std::size_t i = 0; i < count; ++i) {
        work(i);
        if (finished) finished(i);
      }
    } else if (rank_ == 0) {
      hand_out(count, work, finished);
    } else {
      ask_for(work);
    }
  }

  std::vector<std::string> gather_all(const std::string& mine) override {
    const std::uint64_t size = mine.size();
    const std::size_t n = std::size_t(ranks_);
    std::vector<std::uint64_t> sizes(n);
    MPI_Request request;
    MPI_Iallgather(&size, 1, MPI_UINT64_T, sizes.data(), 1, MPI_UINT64_T, comm_, &request);
    wait(&request);
    std::vector<int> counts(n), offsets(n);
    std::uint64_t total = 0;
    for (int r = 0; r < ranks_; ++r) {
      if (total + sizes[r] > std::uint64_t(INT_MAX))
        throw std::runtime_error("the ranks' results of one pass exceed 2 GiB (" + std::to_string(total + sizes[r]) +
                                 " bytes): more than one exchange can carry");
      counts[r] = int(sizes[r]), offsets[r] = int(total);
      total += sizes[r];
    }
    std::string all(total, '\0');
    MPI_Iallgatherv(mine.data(), int(size), MPI_BYTE, all.data(), counts.data(), offsets.data(), MPI_BYTE, comm_,
                    &request);
    wait(&request);
    std::vector<std::string> each(n);
    for (int r = 0; r < ranks_; ++r) each[r] = all.substr(std::size_t(offsets[r]), std::size_t(counts[r]));
    return each;
  }

  void broadcast(std::string* bytes) override {
    std::uint64_t size = bytes->size();
    broadcast_from(0, &size, sizeof size);
    if (rank_ != 0) bytes->assign(size, '\0');
    broadcast_from(0, bytes->data(), size);
  }

  void broadcast_from(int root, void* data, std::size_t size) override {
    char* bytes = static_cast<char*>(data);
    MPI_Request request;
    for (std::size_t at = 0; at < size; at += kPiece) {
      MPI_Ibcast(bytes + at, int(std::min<std::size_t>(kPiece, size - at)), MPI_BYTE, root, comm_, &request);
      wait(&request);
    }
  }

  [[noreturn]] void abort(int exit_code) override {
    MPI_Abort(MPI_COMM_WORLD, exit_code);
    std::_Exit(exit_code);
  }

 private:
  // Rank 0: indices go out in order, to its own main thread and to the
  // other ranks as they ask, until every rank was told there are no more.
  void hand_out(std::size_t count, const std::function<void(std::size_t)>& work,
                const std::function<void(std::size_t)>& finished) {
    std::atomic<std::size_t> next{0};
    std::atomic<bool> stop{false};
    std::mutex reporting;
    auto report = [&](std::size_t i) {
      if (!finished) return;
      std::lock_guard<std::mutex> lock(reporting);
      finished(i);
    };
    auto serve = [&] {
      for (int asking = ranks_ - 1; asking > 0 && !stop;) {
        int waiting = 0;
        MPI_Status status;
        MPI_Iprobe(MPI_ANY_SOURCE, kAsk, comm_, &waiting, &status);
        if (!waiting) {
          pause_briefly();
          continue;
        }
        std::uint64_t done = 0;
        MPI_Recv(&done, 1, MPI_UINT64_T, status.MPI_SOURCE, kAsk, comm_, MPI_STATUS_IGNORE);
        if (done != kNone) report(std::size_t(done));
        std::uint64_t give = next.fetch_add(1);
        if (give >= count) give = kNone, --asking;
        MPI_Send(&give, 1, MPI_UINT64_T, status.MPI_SOURCE, kGive, comm_);
      }
    };
    if (!serve_from_thread_) {
      serve();
      return;
    }
    std::thread server(serve);
    try {
      for (std::size_t i; (i = next.fetch_add(1)) < count;) {
        work(i);
        report(i);
      }
    } catch (...) {
      stop = true;  // the server never blocks for long: each receive is of a message that came
      server.join();
      throw;
    }
    server.join();
  }

  // Another rank: asks rank 0 for an index, works on it, and asks again.
  void ask_for(const std::function<void(std::size_t)>& work) {
    for (std::uint64_t done = kNone;;) {
      MPI_Send(&done, 1, MPI_UINT64_T, 0, kAsk, comm_);
      std::uint64_t give = kNone;
      MPI_Request request;
      MPI_Irecv(&give, 1, MPI_UINT64_T, 0, kGive, comm_, &request);
      wait(&request);
      if (give == kNone) return;
      work(std::size_t(give));
      done = give;
    }
  }

  MPI_Comm comm_ = MPI_COMM_NULL;
  int rank_ = 0, ranks_ = 1;
  bool serve_from_thread_ = true;
};

}  // namespace

std::unique_ptr<WorkSharing> join_mpi_job() { return std::make_unique<MpiWorkSharing>(); }

}  // namespace scan2lod
