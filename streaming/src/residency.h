// Nodes on the store (the GPU in the viewer): uploads, least-recently-used eviction, the byte
// budget.
#pragma once

#include <cstdint>
#include <vector>

#include "node_table.h"

namespace nestlight::streaming::detail {

class ResidentSet {
 public:
  explicit ResidentSet(NodeStore& store) : store_(store) {}

  uint64_t bytes() const { return bytes_; }
  uint32_t count() const { return count_; }
  uint64_t uploads() const { return uploads_; }
  uint64_t evictions() const { return evictions_; }
  uint64_t maxBytes() const { return maxBytes_; }

  // A Ready node becomes Resident (the caller has made room).
  void upload(NodeTable& t, uint32_t idx);
  void evict(NodeTable& t, uint32_t idx);
  void releaseAll(NodeTable& t);

  // Once per frame after cut selection: each cut node leaves the eviction list (keep()), and
  // the nodes that left the cut (in `previousCut`, not in the cut of `frame`) join it.
  void keep(NodeTable& t, uint32_t idx) {
    if (t[idx].inLru) lruRemove(t, idx);
  }
  void addLeavers(NodeTable& t, const std::vector<uint32_t>& previousCut, uint64_t frame);

  // Frees room until `extra` more bytes fit in `budget`: first nodes outside the cut, least
  // recently in it first; then resident nodes of `cut` of lower priority than `forNode` (any
  // priority when kNone: a lowered budget), lowest first. False when not even that makes room.
  // Call beginFrame() after each cut selection.
  bool makeRoom(NodeTable& t, const std::vector<uint32_t>& cut, uint64_t extra, uint64_t budget,
                uint32_t forNode);
  void beginFrame() { victimsSorted_ = false; }

 private:
  void lruAppend(NodeTable& t, uint32_t idx);
  void lruRemove(NodeTable& t, uint32_t idx);

  NodeStore& store_;
  uint64_t bytes_ = 0;
  uint32_t count_ = 0;
  uint64_t uploads_ = 0, evictions_ = 0, maxBytes_ = 0;
  uint32_t lruHead_ = kNone, lruTail_ = kNone;  // head: evicted first
  // Resident cut nodes, lowest priority first, sorted when a frame first needs them.
  std::vector<uint32_t> victims_;
  size_t nextVictim_ = 0;
  bool victimsSorted_ = false;
};

}  // namespace nestlight::streaming::detail
