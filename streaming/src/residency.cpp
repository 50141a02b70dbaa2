// Residency under a byte budget, after Potree's LRU cache of loaded nodes (Schütz 2016, section
// 3.4; Potree 2 keeps it): nodes that leave the cut stay resident as a cache until their memory
// is needed, and go least recently wanted first. Two rules keep the budget exact and the picture
// stable: eviction happens before an upload, never after, so the budget holds at every moment;
// and a node of the current cut is evicted only for a node of higher priority, never for a lower
// one. The list holds only resident nodes outside the cut, ordered by the frame they left it, so
// a frame touches only nodes that entered or left the cut instead of re-sorting every resident
// node by age. A cut node goes only for one of higher priority, lowest priority first.
#include "residency.h"

#include <algorithm>

#include "nestlight/octree/error.h"

namespace nestlight::streaming::detail {

void ResidentSet::upload(NodeTable& t, uint32_t idx) {
  Node& n = t[idx];
  NL_CHECK(n.residency == Residency::Ready && n.prepared);
  n.handle = store_.upload(*n.prepared);
  n.bytes = n.prepared->residentBytes();
  n.bytesKnown = true;
  n.prepared.reset();
  n.residency = Residency::Resident;
  bytes_ += n.bytes;
  maxBytes_ = std::max(maxBytes_, bytes_);
  ++count_;
  ++uploads_;
}

void ResidentSet::evict(NodeTable& t, uint32_t idx) {
  Node& n = t[idx];
  NL_CHECK(n.residency == Residency::Resident);
  if (n.inLru) lruRemove(t, idx);
  store_.release(n.handle);
  n.handle = 0;
  n.residency = Residency::Absent;
  bytes_ -= n.bytes;
  --count_;
  ++evictions_;
}

void ResidentSet::releaseAll(NodeTable& t) {
  for (uint32_t i = 0; i < t.size(); ++i) {
    Node& n = t[i];
    if (n.residency != Residency::Resident) continue;
    store_.release(n.handle);
    n.handle = 0;
    n.inLru = false;
    n.residency = Residency::Absent;
  }
  bytes_ = 0;
  count_ = 0;
  lruHead_ = lruTail_ = kNone;
}

void ResidentSet::lruAppend(NodeTable& t, uint32_t idx) {
  Node& n = t[idx];
  n.lruPrev = lruTail_;
  n.lruNext = kNone;
  if (lruTail_ != kNone)
    t[lruTail_].lruNext = idx;
  else
    lruHead_ = idx;
  lruTail_ = idx;
  n.inLru = true;
}

void ResidentSet::lruRemove(NodeTable& t, uint32_t idx) {
  Node& n = t[idx];
  if (n.lruPrev != kNone)
    t[n.lruPrev].lruNext = n.lruNext;
  else
    lruHead_ = n.lruNext;
  if (n.lruNext != kNone)
    t[n.lruNext].lruPrev = n.lruPrev;
  else
    lruTail_ = n.lruPrev;
  n.lruPrev = n.lruNext = kNone;
  n.inLru = false;
}

void ResidentSet::addLeavers(NodeTable& t, const std::vector<uint32_t>& previousCut,
                             uint64_t frame) {
  // Leavers in reverse priority order: the least important of them goes first.
  for (size_t i = previousCut.size(); i-- > 0;) {
    const uint32_t idx = previousCut[i];
    const Node& n = t[idx];
    if (n.residency == Residency::Resident && n.cutFrame != frame && !n.inLru) lruAppend(t, idx);
  }
}

bool ResidentSet::makeRoom(NodeTable& t, const std::vector<uint32_t>& cut, uint64_t extra,
                           uint64_t budget, uint32_t forNode) {
  if (extra > budget) return false;
  while (bytes_ + extra > budget && lruHead_ != kNone) evict(t, lruHead_);
  if (bytes_ + extra <= budget) return true;
  // Rare: the cut itself does not fit (its byte estimate was low, or the budget just shrank).
  if (!victimsSorted_) {
    victims_.clear();
    for (uint32_t idx : cut)
      if (t[idx].residency == Residency::Resident) victims_.push_back(idx);
    std::sort(victims_.begin(), victims_.end(),
              [&t](uint32_t a, uint32_t b) { return higherPriority(t[b], t[a]); });
    nextVictim_ = 0;
    victimsSorted_ = true;
  }
  while (bytes_ + extra > budget) {
    if (nextVictim_ >= victims_.size()) return false;
    const uint32_t idx = victims_[nextVictim_];
    // Victims only get more important from here on.
    if (forNode != kNone && !higherPriority(t[forNode], t[idx])) return false;
    ++nextVictim_;
    if (t[idx].residency == Residency::Resident) evict(t, idx);
  }
  return true;
}

}  // namespace nestlight::streaming::detail
