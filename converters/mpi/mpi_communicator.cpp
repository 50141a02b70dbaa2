// Communicator over MPI_COMM_WORLD (Open MPI). Errors return to the caller instead of aborting
// in MPI itself only where that helps nothing: a failed collective leaves the job in an unknown
// state, so every failure ends the job (MPI_ERRORS_ARE_FATAL, MPI's default).
// The C API only: Open MPI would bring its deprecated C++ bindings, which need their own library.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>

#include <climits>
#include <cstdio>
#include <cstdlib>

#include "nestlight/converters/mpi.h"
#include "nestlight/octree/error.h"

namespace nestlight {

namespace {

struct Finalizer {
  ~Finalizer() {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized) MPI_Finalize();
  }
};

class MpiCommunicator final : public Communicator {
 public:
  MpiCommunicator() {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  void allreduceSum(std::vector<uint64_t>& v) override {
    if (!v.empty())
      MPI_Allreduce(MPI_IN_PLACE, v.data(), int(v.size()), MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
  }
  void allreduceMax(std::vector<double>& v) override {
    if (!v.empty())
      MPI_Allreduce(MPI_IN_PLACE, v.data(), int(v.size()), MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  }
  std::vector<std::vector<uint8_t>> allgather(const std::vector<uint8_t>& mine) override {
    NL_CHECK(mine.size() < size_t(INT_MAX));
    const size_t ranks = size_t(size_);
    std::vector<int> counts(ranks), displs(ranks);
    int n = int(mine.size());
    MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
    size_t total = 0;
    for (int r = 0; r < size_; ++r) {
      NL_CHECK_MSG(total + size_t(counts[r]) < size_t(INT_MAX), "allgather of 2 GiB or more");
      displs[r] = int(total);
      total += size_t(counts[r]);
    }
    std::vector<uint8_t> all(std::max<size_t>(total, 1));
    MPI_Allgatherv(mine.data(), n, MPI_BYTE, all.data(), counts.data(), displs.data(), MPI_BYTE,
                   MPI_COMM_WORLD);
    std::vector<std::vector<uint8_t>> out(ranks);
    for (int r = 0; r < size_; ++r)
      out[r].assign(all.begin() + displs[r], all.begin() + displs[r] + counts[r]);
    return out;
  }
  std::vector<std::vector<uint8_t>> alltoallv(
      const std::vector<std::vector<uint8_t>>& send) override {
    NL_CHECK(send.size() == size_t(size_));
    const size_t ranks = size_t(size_);
    std::vector<int> sc(ranks), sd(ranks), rc(ranks), rd(ranks);
    size_t st = 0;
    for (int r = 0; r < size_; ++r) {
      NL_CHECK_MSG(st + send[r].size() < size_t(INT_MAX), "alltoallv of 2 GiB or more");
      sc[r] = int(send[r].size());
      sd[r] = int(st);
      st += send[r].size();
    }
    std::vector<uint8_t> sbuf(std::max<size_t>(st, 1));
    for (int r = 0; r < size_; ++r) std::copy(send[r].begin(), send[r].end(), sbuf.begin() + sd[r]);
    MPI_Alltoall(sc.data(), 1, MPI_INT, rc.data(), 1, MPI_INT, MPI_COMM_WORLD);
    size_t rt = 0;
    for (int r = 0; r < size_; ++r) {
      NL_CHECK_MSG(rt + size_t(rc[r]) < size_t(INT_MAX), "alltoallv of 2 GiB or more");
      rd[r] = int(rt);
      rt += size_t(rc[r]);
    }
    std::vector<uint8_t> rbuf(std::max<size_t>(rt, 1));
    MPI_Alltoallv(sbuf.data(), sc.data(), sd.data(), MPI_BYTE, rbuf.data(), rc.data(), rd.data(),
                  MPI_BYTE, MPI_COMM_WORLD);
    std::vector<std::vector<uint8_t>> out(ranks);
    for (int r = 0; r < size_; ++r)
      out[r].assign(rbuf.begin() + rd[r], rbuf.begin() + rd[r] + rc[r]);
    return out;
  }
  void barrier() override { MPI_Barrier(MPI_COMM_WORLD); }
  [[noreturn]] void abort(int code) override {
    std::fflush(stdout);
    std::fflush(stderr);
    MPI_Abort(MPI_COMM_WORLD, code);
    std::_Exit(code);  // MPI_Abort does not return; the compiler does not know
  }

 private:
  int rank_ = 0, size_ = 1;
};

}  // namespace

std::unique_ptr<Communicator> mpiWorld() {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (!initialised) {
    int provided = 0;
    // Only the thread that calls the builder's collectives talks to MPI.
    if (MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS)
      throw Error("--mpi: MPI could not be initialised (start the job with mpirun)");
    static Finalizer finalizer;
  }
  return std::make_unique<MpiCommunicator>();
}

}  // namespace nestlight
