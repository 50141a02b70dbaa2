// Loader threads after Potree's node loading (Schütz, Ohrhallinger, Wimmer 2020, section 5):
// workers take the most important pending node, read its hierarchy chunk when the node is a
// proxy (Potree 2 loads hierarchy and geometry the same way, on demand) and its payload, decode
// it, and hand the result back; the render thread only uploads. The queue is a plain vector that
// the render thread replaces each frame, so re-prioritising costs one swap under the lock, and
// a request is taken only by moving its node Queued -> Loading, so cancellation needs no search.
#include "loaders.h"

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include "nestlight/octree/error.h"

namespace nestlight::streaming::detail {

namespace {
constexpr int kLoaderNice = 10;
}  // namespace

BadNodeLog::BadNodeLog() {
  callback_ = [](const BadNode& b) {
    std::fprintf(stderr, "nestlight: streaming: %s (not drawn, not requested again)\n",
                 b.message.c_str());
  };
}

void BadNodeLog::setCallback(std::function<void(const BadNode&)> f) {
  std::lock_guard<std::mutex> lock(callMutex_);
  callback_ = std::move(f);
}

void BadNodeLog::report(const NodeKey& key, const std::string& message) {
  BadNode b{key, message};
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!seen_.insert(key).second) return;
    list_.push_back(b);
  }
  std::lock_guard<std::mutex> lock(callMutex_);
  if (callback_) callback_(b);
}

std::vector<BadNode> BadNodeLog::list() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return list_;
}

Loaders::Loaders(OctreeReader& reader, NodeStore& store, BadNodeLog& log)
    : reader_(reader), store_(store), log_(log) {}

Loaders::~Loaders() {
  stop();
}

void Loaders::setThreads(int n) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (stop_) return;
  active_ = static_cast<size_t>(std::max(n, 1));
  while (threads_.size() < active_) threads_.emplace_back(&Loaders::run, this, threads_.size());
  wake_.notify_all();
}

size_t Loaders::replaceQueue(std::vector<LoadRequest>& fresh) {
  size_t returned;
  bool wake;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    std::swap(queue_, fresh);
    returned = head_;
    head_ = 0;
    // A busy loader looks at the queue when it finishes; waking costs the render thread time.
    wake = idle_ > 0 && !queue_.empty();
  }
  if (wake) wake_.notify_all();
  return returned;
}

void Loaders::takeResults(std::vector<LoadResult>& out) {
  out.clear();
  std::lock_guard<std::mutex> lock(doneMutex_);
  std::swap(out, done_);
}

void Loaders::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (auto& t : threads_) t.join();
  threads_.clear();
}

void Loaders::run(size_t id) {
#ifdef __linux__
  // Below the render thread: on a machine with few cores a loader woken by update() would
  // otherwise preempt the render thread inside that very call (measured: 2-8 ms stalls on two
  // cores). SCHED_BATCH threads never preempt on wake-up; nice makes them yield the core sooner.
  sched_param param{};
  ::pthread_setschedparam(::pthread_self(), SCHED_BATCH, &param);
  ::setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), kLoaderNice);
#endif
  for (;;) {
    LoadRequest r;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      ++idle_;
      wake_.wait(lock, [&] { return stop_ || (id < active_ && head_ < queue_.size()); });
      --idle_;
      if (stop_) return;
      r = queue_[head_++];
      LoadState expected = LoadState::Queued;
      // Cancelled by the render thread, or a stale copy of a request already taken.
      if (!r.state->compare_exchange_strong(expected, LoadState::Loading)) continue;
      inFlight_.fetch_add(1, std::memory_order_relaxed);
    }
    LoadResult res = load(r);
    std::lock_guard<std::mutex> lock(doneMutex_);
    done_.push_back(std::move(res));
    inFlight_.fetch_sub(1, std::memory_order_relaxed);
  }
}

LoadResult Loaders::load(const LoadRequest& r) {
  LoadResult res;
  res.node = r.node;
  const uint64_t before = OctreeReader::threadBytesRead();
  try {
    HierarchyEntry entry = r.entry;
    if (r.hierarchy || entry.type == NodeType::Proxy) {
      auto e = reader_.ensureLoaded(r.key);
      if (!e) throw Error(reader_.dir().string(), "node " + r.key.name(), "not in the hierarchy");
      entry = *e;
      if (r.hierarchy) {
        if (!collectWalk(reader_, r.key, entry, reader_.metadata().hierarchyStep, res.hierarchy))
          throw Error((reader_.dir() / reader_.metadata().hierarchyFile).string(),
                      "node " + r.key.name(), "hierarchy below the node is incomplete");
        res.hasHierarchy = true;
      }
    }
    if (r.payload) {
      PointBuffer points = reader_.readNode(r.key);
      auto p = std::make_unique<PreparedNode>();
      p->key = r.key;
      p->numPoints = static_cast<uint32_t>(points.size());
      store_.prepare(r.key, std::move(points), *p);
      res.prepared = std::move(p);
    }
  } catch (const std::exception& e) {
    res.failed = true;
    res.hasHierarchy = false;
    res.hierarchy.clear();
    res.prepared.reset();
    log_.report(r.key, "node " + r.key.name() + ": " + e.what());
  }
  res.bytesRead = OctreeReader::threadBytesRead() - before;
  return res;
}

}  // namespace nestlight::streaming::detail
