// The scheduler's own copy of the hierarchy, grown as loader threads read hierarchy chunks.
//
// Potree 2 (Schütz, Ohrhallinger, Wimmer 2020, section 4.3) pages the hierarchy in chunks and its
// viewer learns a proxy node's subtree only when the node's chunk has been loaded; so does this
// table. The render thread owns it and reads nothing but it each frame, so cut selection never
// touches the reader (whose chunks are read by loaders) and never waits on a file. Per-node state
// lives here too, in one flat array indexed by node number, so that a frame walks memory it owns
// without hashing keys.
#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <utility>
#include <vector>

#include "nestlight/octree/hierarchy.h"
#include "nestlight/octree/metadata.h"
#include "nestlight/octree/node_key.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/streaming/node_store.h"

namespace nestlight::streaming::detail {

inline constexpr uint32_t kNone = UINT32_MAX;

// Shared with loader threads through an atomic: a loader takes a request only by moving its node
// Queued -> Loading, so a request cancelled by the render thread (Queued -> Idle) is never taken
// and a node queued twice is loaded once.
enum class LoadState : uint8_t { Idle, Queued, Loading };

enum class Residency : uint8_t { Absent, Ready, Resident, Bad };

// Laid out for the frame loop: cut selection and the draw list read the first two cache lines of
// every node in the cut each frame; the rest is touched only when a node loads or moves.
struct alignas(64) Node {
  // The node's cube clipped to the scan's tight bounds: culling box and bounding sphere.
  double center[3] = {0, 0, 0};
  double half[3] = {0, 0, 0};
  double radius = 0;
  double spacing = 0;  // Metadata::spacing / 2^level

  NodeKey key;
  uint64_t bytes = 0;     // resident bytes (NodeStore format) once known
  uint64_t handle = 0;    // while Resident
  uint64_t cutFrame = 0;  // last frame in the cut
  double weight = 0;      // priority in that frame: projected radius, pixels
  uint32_t numPoints = 0;
  uint32_t firstChild = kNone;  // children, contiguous in childMask bit order; kNone: unknown
  uint32_t parent = kNone;
  uint8_t childMask = 0;
  Residency residency = Residency::Absent;
  bool bytesKnown : 1 = false;  // `bytes` comes from a prepare() of this node
  bool refine : 1 = false;      // this frame: the view wants its children
  bool inLru : 1 = false;       // resident, outside the cut, on the eviction list

  HierarchyEntry entry;  // a Proxy until a loader has read the node's own chunk
  std::atomic<LoadState>* load = nullptr;
  std::unique_ptr<PreparedNode> prepared;  // while Ready
  uint64_t queuedFrame = 0;                // last frame it was put in the load queue
  uint32_t lruPrev = kNone, lruNext = kNone;
};

// Whether a hierarchy walk descends below `e`, `depth` levels under the walk's root. Loaders
// (collecting a chunk's entries with OctreeReader::peek) and the table (integrating them) walk by
// this same rule, breadth first, so the entries arrive in the order the table allocates nodes.
// Priority order between two nodes of the same cut: larger on screen first, then NodeKey order.
inline bool higherPriority(const Node& a, const Node& b) {
  return a.weight != b.weight ? a.weight > b.weight : a.key < b.key;
}

inline bool walkBelow(const HierarchyEntry& e, uint32_t depth, uint32_t step) {
  return e.type == NodeType::Inner && e.childMask != 0 && depth < step;
}

using EntryList = std::vector<std::pair<NodeKey, HierarchyEntry>>;

class NodeTable {
 public:
  explicit NodeTable(const Metadata& meta);

  uint32_t size() const { return static_cast<uint32_t>(nodes_.size()); }
  Node& operator[](uint32_t i) { return nodes_[i]; }
  const Node& operator[](uint32_t i) const { return nodes_[i]; }
  uint32_t hierarchyStep() const { return step_; }

  // Adds the root (the table must be empty).
  void addRoot(const HierarchyEntry& e);
  // Takes a loader's breadth-first walk below node `at` (list[0] is `at` itself). Returns false
  // when the list does not match the walk (a damaged hierarchy); the table is then unchanged
  // below `at` except for entries already taken.
  bool integrate(uint32_t at, const EntryList& list);
  // Children exist but are not in the table yet: a loader must read the node's chunk.
  static bool needsHierarchy(const Node& n) { return n.childMask != 0 && n.firstChild == kNone; }
  // World cube of a node (DrawNode::worldBounds).
  Box3d cube(const NodeKey& k) const;

 private:
  uint32_t addNode(const NodeKey& key, const HierarchyEntry& e, uint32_t parent);

  const Metadata& meta_;
  uint32_t step_;
  std::vector<Node> nodes_;
  std::deque<std::atomic<LoadState>> loadStates_;  // stable addresses for the loaders
  std::vector<uint32_t> walkScratch_;
};

// Collects, with OctreeReader::peek only, the breadth-first walk below `root` that
// NodeTable::integrate expects. False when an entry the walk needs is not loaded.
bool collectWalk(const OctreeReader& reader, const NodeKey& root, const HierarchyEntry& rootEntry,
                 uint32_t step, EntryList& out);

}  // namespace nestlight::streaming::detail
