// The collective operations a conversion spread over several processes needs (`convert --mpi`),
// behind an interface so that the builder does not depend on MPI: one process is a job of one
// rank (selfCommunicator), an MPI job is the MPI implementation (nestlight/converters/mpi.h, built
// when Open MPI is installed). Every rank calls each operation in the same order; an operation
// returns once every rank has called it.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

namespace nestlight {

class Communicator {
 public:
  virtual ~Communicator() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  // Element-wise over the ranks, in place (every rank passes as many values).
  virtual void allreduceSum(std::vector<uint64_t>& values) = 0;
  virtual void allreduceMax(std::vector<double>& values) = 0;
  // Every rank's bytes, to every rank, in rank order.
  virtual std::vector<std::vector<uint8_t>> allgather(const std::vector<uint8_t>& mine) = 0;
  // send[d]: the bytes for rank d (send.size() == size()); returns what each rank sent this one.
  // Each rank receives less than 2 GiB per call (MPI's counts are int): callers exchange in rounds.
  virtual std::vector<std::vector<uint8_t>> alltoallv(
      const std::vector<std::vector<uint8_t>>& send) = 0;
  virtual void barrier() = 0;
  // Ends every rank of the job at once, with exit code `code` (the error was printed first): a
  // rank that failed cannot leave the others waiting in a collective.
  [[noreturn]] virtual void abort(int code) = 0;

  // Helpers over the above.
  uint64_t sum(uint64_t v) {
    std::vector<uint64_t> x{v};
    allreduceSum(x);
    return x[0];
  }
  bool any(bool v) { return sum(v ? 1 : 0) > 0; }
};

// A job of one process (rank 0 of 1): every operation returns its input.
std::unique_ptr<Communicator> selfCommunicator();

// A job of `ranks` ranks inside this process, one per thread that calls the builder with its
// own communicator: the distributed build checked without MPI (tests under the sanitizers).
// abort() ends the process.
std::vector<std::unique_ptr<Communicator>> threadGroup(int ranks);

}  // namespace nestlight
