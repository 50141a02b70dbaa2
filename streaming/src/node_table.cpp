// The scheduler's copy of the paged hierarchy, after Potree 2 (Schütz, Ohrhallinger, Wimmer 2020,
// section 4.3): a proxy's subtree joins the table when a loader has read its chunk. Children are
// allocated together and contiguously so that cut selection reaches them without a hash lookup.
#include "node_table.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "nestlight/octree/error.h"

namespace nestlight::streaming::detail {

NodeTable::NodeTable(const Metadata& meta) : meta_(meta), step_(meta.hierarchyStep) {
  // The table never holds more nodes than the octree: reserving them avoids moving the array
  // while the view explores (bounded, so that a lying metadata cannot ask for too much).
  nodes_.reserve(static_cast<size_t>(std::min<uint64_t>(meta.nodes + 1, 1u << 20)));
}

Box3d NodeTable::cube(const NodeKey& k) const {
  return meta_.nodeBounds(k.level, k.x, k.y, k.z);
}

uint32_t NodeTable::addNode(const NodeKey& key, const HierarchyEntry& e, uint32_t parent) {
  const uint32_t idx = size();
  Node& n = nodes_.emplace_back();
  n.key = key;
  n.entry = e;
  n.numPoints = e.numPoints;
  n.childMask = e.childMask;
  n.parent = parent;
  n.load = &loadStates_.emplace_back(LoadState::Idle);
  // Culling and priority use the cube clipped to the scan's tight bounds: a flat scan in a tall
  // cube would otherwise look near (and big) from far above it.
  const Box3d c = cube(key);
  const Box3d& b = meta_.bounds;
  for (int a = 0; a < 3; ++a) {
    double lo = c.min[a], hi = c.max[a];
    if (!b.empty() && b.min[a] <= hi && b.max[a] >= lo) {
      lo = std::max(lo, b.min[a]);
      hi = std::min(hi, b.max[a]);
    }
    n.center[a] = 0.5 * (lo + hi);
    n.half[a] = 0.5 * (hi - lo);
  }
  n.radius = std::sqrt(n.half[0] * n.half[0] + n.half[1] * n.half[1] + n.half[2] * n.half[2]);
  n.spacing = meta_.levelSpacing(key.level);
  return idx;
}

void NodeTable::addRoot(const HierarchyEntry& e) {
  NL_CHECK(nodes_.empty());
  addNode(NodeKey::root(), e, kNone);
}

bool NodeTable::integrate(uint32_t at, const EntryList& list) {
  if (list.empty() || list[0].first != nodes_[at].key) return false;
  const uint32_t rootLevel = nodes_[at].key.level;
  // walkScratch_[i] is the table index of list[i]: the walk's own queue.
  walkScratch_.assign(list.size(), kNone);
  walkScratch_[0] = at;
  size_t next = 1;
  for (size_t i = 0; i < list.size(); ++i) {
    const uint32_t idx = walkScratch_[i];
    if (idx == kNone || list[i].first != nodes_[idx].key) return false;
    const HierarchyEntry& e = list[i].second;
    // A node already in the table keeps its children; its entry may only become more exact
    // (a proxy's real entry) and must describe the same children.
    if (nodes_[idx].entry.childMask != e.childMask) return false;
    if (nodes_[idx].entry.type == NodeType::Proxy || i == 0) {
      nodes_[idx].entry = e;
      nodes_[idx].numPoints = e.numPoints;
    }
    if (!walkBelow(e, list[i].first.level - rootLevel, step_)) continue;
    if (nodes_[idx].firstChild == kNone) {
      const NodeKey key = nodes_[idx].key;
      uint32_t first = kNone;
      size_t j = next;
      for (int c = 0; c < 8; ++c) {
        if (!(e.childMask & (1u << c))) continue;
        if (j >= list.size() || list[j].first != key.child(c)) return false;
        const uint32_t child = addNode(key.child(c), list[j].second, idx);
        if (first == kNone) first = child;
        ++j;
      }
      nodes_[idx].firstChild = first;
    }
    for (uint32_t c = nodes_[idx].firstChild, k = 0; k < uint32_t(std::popcount(e.childMask));
         ++k, ++c) {
      if (next >= list.size()) return false;
      walkScratch_[next++] = c;
    }
  }
  return next == list.size();
}

bool collectWalk(const OctreeReader& reader, const NodeKey& root, const HierarchyEntry& rootEntry,
                 uint32_t step, EntryList& out) {
  out.clear();
  out.emplace_back(root, rootEntry);
  for (size_t i = 0; i < out.size(); ++i) {
    const NodeKey k = out[i].first;
    const HierarchyEntry e = out[i].second;
    if (!walkBelow(e, k.level - root.level, step)) continue;
    for (int c = 0; c < 8; ++c) {
      if (!(e.childMask & (1u << c))) continue;
      auto ce = reader.peek(k.child(c));
      if (!ce) return false;
      out.emplace_back(k.child(c), *ce);
    }
  }
  return true;
}

}  // namespace nestlight::streaming::detail
