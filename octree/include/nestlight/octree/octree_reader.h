// Reads an octree folder written by OctreeWriter. Opening reads metadata.json and the root
// hierarchy chunk only; deeper chunks are read when a node below them is asked for. Node reads
// are thread-safe (pread) and verify the payload checksum.
//
// A viewer's render thread must never wait on a file: it asks peek(), which answers from the
// chunks already read, and leaves reading to loader threads (ensureLoaded(), readNode()). No
// method holds the reader's lock while it reads a file, so peek() never waits on I/O either.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "nestlight/octree/error.h"
#include "nestlight/octree/hierarchy.h"
#include "nestlight/octree/metadata.h"
#include "nestlight/octree/point_buffer.h"

namespace nestlight {

class OctreeReader {
 public:
  // Throws nestlight::Error naming the file at fault.
  explicit OctreeReader(const std::filesystem::path& dir);
  ~OctreeReader();

  const Metadata& metadata() const { return meta_; }
  const std::filesystem::path& dir() const { return dir_; }

  // The node's entry (never a proxy), reading hierarchy chunks as needed; nullopt if absent.
  std::optional<HierarchyEntry> node(const NodeKey& key);
  std::vector<NodeKey> children(const NodeKey& key);

  // Non-blocking: never reads a file. The node's entry as far as the chunks already read know
  // it; nullopt when there is no such node or it lies below a chunk not read yet (see
  // hierarchyPending()). A Proxy entry (its childMask and numPoints are valid) means the node's
  // own chunk, which holds its payload location and its children, is not read yet.
  std::optional<HierarchyEntry> peek(const NodeKey& key) const;
  // Non-blocking: true when `key` or one of its ancestors is a proxy whose chunk is not read yet,
  // so that its entry or its children need ensureLoaded().
  bool hierarchyPending(const NodeKey& key) const;
  // Reads the hierarchy chunks down to `key` (blocking: for loader threads) and returns its real
  // entry (never a proxy), nullopt if there is no such node. A damaged chunk on the way throws
  // nestlight::Error naming hierarchy.bin, on this and every later call.
  std::optional<HierarchyEntry> ensureLoaded(const NodeKey& key);
  // Every node, breadth first (reads the whole hierarchy).
  std::vector<std::pair<NodeKey, HierarchyEntry>> allNodes();

  // Reads, checks and decodes a node; positions come back in the octree's global integer grid.
  // Throws nestlight::Error on a checksum mismatch or undecodable payload.
  PointBuffer readNode(const NodeKey& key);
  // The raw payload bytes (for verify and benchmarks).
  std::vector<uint8_t> readPayload(const HierarchyEntry& e);

  uint64_t hierarchyBytesRead() const { return hierarchyBytesRead_.load(); }
  uint64_t payloadBytesRead() const { return payloadBytesRead_.load(); }

  // Calls made by the calling thread, to any reader, of the methods that may read a file
  // (everything above but metadata(), peek() and hierarchyPending()), and the bytes they read:
  // tests count them on a render thread, which must make none.
  static uint64_t threadReadCalls();
  static uint64_t threadBytesRead();

 private:
  std::optional<HierarchyEntry> resolve(const NodeKey& key);
  void loadChunk(std::unique_lock<std::mutex>& lock, const NodeKey& root, uint64_t offset,
                 uint64_t size, uint64_t checksum);

  std::filesystem::path dir_;
  Metadata meta_;
  int payloadFd_ = -1;
  int hierarchyFd_ = -1;
  mutable std::mutex mutex_;
  std::condition_variable chunkRead_;  // a chunk that another thread was reading is in
  std::unordered_map<NodeKey, HierarchyEntry, NodeKeyHash> entries_;  // proxies until loaded
  std::atomic<uint64_t> hierarchyBytesRead_{0};
  std::atomic<uint64_t> payloadBytesRead_{0};
  std::unordered_set<uint64_t> loadedChunks_;   // offsets of the hierarchy chunks read or reading
  std::unordered_set<uint64_t> readingChunks_;  // being read by some thread, without the lock
  std::unordered_map<uint64_t, Error> failedChunks_;  // damaged chunks: the error, rethrown
};

}  // namespace nestlight
