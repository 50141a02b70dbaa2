// Where resident nodes live: the GPU in the viewer, plain memory in tests and the stress tool.
// The scheduler never touches GL; it talks to a NodeStore.
#pragma once

#include <cstdint>
#include <vector>

#include "nestlight/octree/node_key.h"
#include "nestlight/octree/point_buffer.h"

namespace nestlight::streaming {

// A node as the loader threads leave it: decoded and converted to the store's upload format,
// ready for one copy on the render thread.
struct PreparedNode {
  NodeKey key;
  uint32_t numPoints = 0;
  std::vector<uint8_t> bytes;  // the points as upload() copies them
  // Further per-node data a store prepares beside the points (a GI method's hierarchy over the
  // node, an HDR colour layer), each uploaded as a buffer of its own and freed with the node.
  std::vector<std::vector<uint8_t>> layers;
  // What the node costs resident: its points and every layer, counted against Budgets::gpuBytes.
  uint64_t residentBytes() const {
    uint64_t b = bytes.size();
    for (const auto& l : layers) b += l.size();
    return b;
  }
};

class NodeStore {
 public:
  virtual ~NodeStore() = default;
  // Loader threads: decoded points (global integer grid) -> upload format. Must be thread-safe.
  virtual void prepare(const NodeKey& key, PointBuffer&& points, PreparedNode& out) const = 0;
  // Render thread: makes the node resident and returns a handle (> 0) for draw lists.
  virtual uint64_t upload(const PreparedNode& node) = 0;
  // Render thread: frees a handle returned by upload().
  virtual void release(uint64_t handle) = 0;
};

}  // namespace nestlight::streaming
