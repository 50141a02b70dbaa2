// A NodeStore in plain memory, for tests, the stress tool and benchmarks: what the viewer's GPU
// store does, without GL. Each point becomes 16 bytes, the layout a GPU store would upload:
// float x, y, z relative to the node's cube min corner (world units, so a national-grid scan
// keeps millimetres) and RGBA8 colour (white without rgb).
//
// It also checks its callers: every handle released exactly once, live bytes counted.
#pragma once

#include <cstdint>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "nestlight/octree/metadata.h"
#include "nestlight/streaming/node_store.h"

namespace nestlight::streaming {

class MemoryStore : public NodeStore {
 public:
  static constexpr size_t kBytesPerPoint = 16;

  // `keepBytes` false: upload() records sizes only (benchmarks of the scheduler, not of memcpy).
  explicit MemoryStore(const Metadata& meta, bool keepBytes = true);

  void prepare(const NodeKey& key, PointBuffer&& points, PreparedNode& out) const override;
  uint64_t upload(const PreparedNode& node) override;
  void release(uint64_t handle) override;

  uint64_t liveHandles() const;
  uint64_t liveBytes() const;
  uint64_t maxLiveBytes() const;
  uint64_t uploads() const;
  uint64_t releases() const;
  // release() of a handle that is not live (twice, or never uploaded): must stay 0.
  uint64_t badReleases() const;
  // The node a live handle holds, and its bytes (empty when not live or not kept).
  NodeKey keyOf(uint64_t handle) const;
  std::vector<uint8_t> bytesOf(uint64_t handle) const;

 private:
  struct Entry {
    NodeKey key;
    uint64_t size = 0;
    std::vector<uint8_t> bytes;
  };
  const Metadata& meta_;
  int rgb_ = -1;  // attribute index of rgb
  bool keepBytes_;
  mutable std::mutex mutex_;
  std::unordered_map<uint64_t, Entry> live_;
  uint64_t nextHandle_ = 1;
  uint64_t liveBytes_ = 0, maxLiveBytes_ = 0, uploads_ = 0, releases_ = 0, badReleases_ = 0;
};

}  // namespace nestlight::streaming
