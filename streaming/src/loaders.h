// The load queue and the loader threads: everything that reads a file.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_set>
#include <vector>

#include "nestlight/streaming/streamer.h"
#include "node_table.h"

namespace nestlight::streaming::detail {

struct LoadRequest {
  uint32_t node = kNone;
  std::atomic<LoadState>* state = nullptr;
  NodeKey key;
  HierarchyEntry entry;    // as the table knows it: a proxy until the node's chunk is read
  bool hierarchy = false;  // read the node's chunk and collect the walk below it
  bool payload = false;    // read, check, decode and prepare the payload
};

struct LoadResult {
  uint32_t node = kNone;
  bool failed = false;
  bool hasHierarchy = false;
  EntryList hierarchy;
  std::unique_ptr<PreparedNode> prepared;
  uint64_t bytesRead = 0;
};

// Bad nodes, each reported once through the callback, from the loader that found it.
class BadNodeLog {
 public:
  BadNodeLog();
  void setCallback(std::function<void(const BadNode&)> f);
  void report(const NodeKey& key, const std::string& message);
  std::vector<BadNode> list() const;

 private:
  mutable std::mutex mutex_;
  std::mutex callMutex_;  // callbacks one at a time, without holding mutex_
  std::function<void(const BadNode&)> callback_;
  std::unordered_set<NodeKey, NodeKeyHash> seen_;
  std::vector<BadNode> list_;
};

class Loaders {
 public:
  Loaders(OctreeReader& reader, NodeStore& store, BadNodeLog& log);
  ~Loaders();

  // Render thread. Never waits for a load: more threads start at once, fewer park themselves.
  void setThreads(int n);
  // Render thread: `fresh` becomes the queue (highest priority first); on return it holds the
  // previous queue, whose requests from index `returned` on were never taken.
  size_t replaceQueue(std::vector<LoadRequest>& fresh);
  // Render thread: moves finished loads into `out` (cleared first).
  void takeResults(std::vector<LoadResult>& out);
  uint32_t inFlight() const { return inFlight_.load(std::memory_order_relaxed); }
  // Stops every thread after its current load and joins them; the untaken requests and the
  // finished loads are left for the caller (queue(), takeResults()).
  void stop();
  const std::vector<LoadRequest>& queue() const { return queue_; }
  size_t queueHead() const { return head_; }

 private:
  void run(size_t id);
  LoadResult load(const LoadRequest& r);

  OctreeReader& reader_;
  NodeStore& store_;
  BadNodeLog& log_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::vector<LoadRequest> queue_;
  size_t head_ = 0;
  size_t active_ = 0;
  size_t idle_ = 0;  // threads waiting for work
  bool stop_ = false;
  std::vector<std::thread> threads_;
  std::atomic<uint32_t> inFlight_{0};
  std::mutex doneMutex_;
  std::vector<LoadResult> done_;
};

}  // namespace nestlight::streaming::detail
