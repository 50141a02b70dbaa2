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
#include <string>

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
    std::vector<int> counts(static_cast<size_t>(size_));
    int n = int(mine.size());
    MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
    const std::vector<int> displs = offsets(counts, "allgather");
    std::vector<uint8_t> all(std::max<size_t>(size_t(displs.back()), 1));
    MPI_Allgatherv(mine.data(), n, MPI_BYTE, all.data(), counts.data(), displs.data(), MPI_BYTE,
                   MPI_COMM_WORLD);
    return split(all, counts, displs);
  }
  std::vector<std::vector<uint8_t>> alltoallv(
      const std::vector<std::vector<uint8_t>>& send) override {
    NL_CHECK(send.size() == size_t(size_));
    std::vector<int> sc(static_cast<size_t>(size_)), rc(static_cast<size_t>(size_));
    for (int r = 0; r < size_; ++r) {
      NL_CHECK_MSG(send[r].size() < size_t(INT_MAX), "alltoallv of 2 GiB or more");
      sc[r] = int(send[r].size());
    }
    const std::vector<int> sd = offsets(sc, "alltoallv");
    std::vector<uint8_t> sbuf(std::max<size_t>(size_t(sd.back()), 1));
    for (int r = 0; r < size_; ++r) std::copy(send[r].begin(), send[r].end(), sbuf.begin() + sd[r]);
    MPI_Alltoall(sc.data(), 1, MPI_INT, rc.data(), 1, MPI_INT, MPI_COMM_WORLD);
    const std::vector<int> rd = offsets(rc, "alltoallv");
    std::vector<uint8_t> rbuf(std::max<size_t>(size_t(rd.back()), 1));
    MPI_Alltoallv(sbuf.data(), sc.data(), sd.data(), MPI_BYTE, rbuf.data(), rc.data(), rd.data(),
                  MPI_BYTE, MPI_COMM_WORLD);
    return split(rbuf, rc, rd);
  }
  void barrier() override { MPI_Barrier(MPI_COMM_WORLD); }
  [[noreturn]] void abort(int code) override {
    std::fflush(stdout);
    std::fflush(stderr);
    MPI_Abort(MPI_COMM_WORLD, code);
    std::_Exit(code);  // MPI_Abort does not return; the compiler does not know
  }

 private:
  // Each rank's offset in one buffer of `counts` bytes in rank order, and the total after them
  // (MPI counts are int: a call moves less than 2 GiB).
  static std::vector<int> offsets(const std::vector<int>& counts, const char* what) {
    std::vector<int> at(counts.size() + 1, 0);
    size_t total = 0;
    for (size_t r = 0; r < counts.size(); ++r) {
      at[r] = int(total);
      total += size_t(counts[r]);
      NL_CHECK_MSG(total < size_t(INT_MAX), std::string(what) + " of 2 GiB or more");
    }
    at.back() = int(total);
    return at;
  }
  // One buffer back into each rank's bytes.
  static std::vector<std::vector<uint8_t>> split(const std::vector<uint8_t>& all,
                                                 const std::vector<int>& counts,
                                                 const std::vector<int>& at) {
    std::vector<std::vector<uint8_t>> out(counts.size());
    for (size_t r = 0; r < counts.size(); ++r)
      out[r].assign(all.begin() + at[r], all.begin() + at[r] + counts[r]);
    return out;
  }
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
