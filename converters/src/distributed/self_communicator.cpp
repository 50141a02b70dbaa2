#include <algorithm>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <mutex>

#include "nestlight/converters/communicator.h"
#include "nestlight/octree/error.h"

namespace nestlight {

namespace {

class SelfCommunicator final : public Communicator {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  void allreduceSum(std::vector<uint64_t>&) override {}
  void allreduceMax(std::vector<double>&) override {}
  std::vector<std::vector<uint8_t>> allgather(const std::vector<uint8_t>& mine) override {
    return {mine};
  }
  std::vector<std::vector<uint8_t>> alltoallv(
      const std::vector<std::vector<uint8_t>>& send) override {
    NL_CHECK(send.size() == 1);
    return send;
  }
  void barrier() override {}
  [[noreturn]] void abort(int code) override { std::exit(code); }
};

// What the ranks of a thread group share: a barrier that counts generations, and each rank's
// outgoing messages, read by the others between two barriers.
struct GroupState {
  explicit GroupState(int n) : ranks(n), slots(size_t(n)) {}
  void barrier() {
    std::unique_lock<std::mutex> lock(m);
    const uint64_t g = generation;
    if (++arrived == ranks) {
      arrived = 0;
      ++generation;
      cv.notify_all();
    } else {
      cv.wait(lock, [&] { return generation != g; });
    }
  }
  const int ranks;
  std::mutex m;
  std::condition_variable cv;
  int arrived = 0;
  uint64_t generation = 0;
  std::vector<std::vector<std::vector<uint8_t>>> slots;  // [from][to]
};

class ThreadCommunicator final : public Communicator {
 public:
  ThreadCommunicator(std::shared_ptr<GroupState> g, int rank) : g_(std::move(g)), rank_(rank) {}
  int rank() const override { return rank_; }
  int size() const override { return g_->ranks; }
  void allreduceSum(std::vector<uint64_t>& v) override {
    const auto all = allgather(bytesOf(v));
    for (size_t i = 0; i < v.size(); ++i) {
      v[i] = 0;
      for (const auto& b : all) v[i] += valueAt<uint64_t>(b, i);
    }
  }
  void allreduceMax(std::vector<double>& v) override {
    const auto all = allgather(bytesOf(v));
    for (size_t i = 0; i < v.size(); ++i) {
      v[i] = -std::numeric_limits<double>::infinity();
      for (const auto& b : all) v[i] = std::max(v[i], valueAt<double>(b, i));
    }
  }
  std::vector<std::vector<uint8_t>> allgather(const std::vector<uint8_t>& mine) override {
    return alltoallv(std::vector<std::vector<uint8_t>>(size_t(g_->ranks), mine));
  }
  std::vector<std::vector<uint8_t>> alltoallv(
      const std::vector<std::vector<uint8_t>>& send) override {
    NL_CHECK(send.size() == size_t(g_->ranks));
    g_->slots[size_t(rank_)] = send;
    g_->barrier();
    std::vector<std::vector<uint8_t>> recv(size_t(g_->ranks));
    for (int s = 0; s < g_->ranks; ++s) recv[size_t(s)] = g_->slots[size_t(s)][size_t(rank_)];
    g_->barrier();  // every rank has read before any writes its next message
    return recv;
  }
  void barrier() override { g_->barrier(); }
  [[noreturn]] void abort(int code) override { std::_Exit(code); }

 private:
  template <class T>
  static std::vector<uint8_t> bytesOf(const std::vector<T>& v) {
    std::vector<uint8_t> b(v.size() * sizeof(T));
    if (!b.empty()) std::memcpy(b.data(), v.data(), b.size());
    return b;
  }
  template <class T>
  static T valueAt(const std::vector<uint8_t>& b, size_t i) {
    NL_CHECK((i + 1) * sizeof(T) <= b.size());
    T x;
    std::memcpy(&x, b.data() + i * sizeof(T), sizeof(T));
    return x;
  }
  std::shared_ptr<GroupState> g_;
  int rank_;
};

}  // namespace

std::vector<std::unique_ptr<Communicator>> threadGroup(int ranks) {
  NL_CHECK(ranks >= 1);
  auto g = std::make_shared<GroupState>(ranks);
  std::vector<std::unique_ptr<Communicator>> out;
  for (int r = 0; r < ranks; ++r) out.push_back(std::make_unique<ThreadCommunicator>(g, r));
  return out;
}

std::unique_ptr<Communicator> selfCommunicator() {
  return std::make_unique<SelfCommunicator>();
}

}  // namespace nestlight
