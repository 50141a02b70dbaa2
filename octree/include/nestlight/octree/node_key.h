// Octree node addressing.
//
// A node is (level, x, y, z) with x, y, z in [0, 2^level). Child i of a node has the octant bits
// i = (dx << 2) | (dy << 1) | dz, as in Potree, so the name of a node is "r" followed by one
// digit per level ("r", "r0", "r07", ...). Node cubes are exact in the octree's integer grid: the
// root cube is `cubeSize` units wide (a power of two) and a node at level l is cubeSize >> l wide.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

namespace nestlight {

struct NodeKey {
  uint32_t level = 0;
  uint32_t x = 0, y = 0, z = 0;

  static NodeKey root() { return {}; }
  NodeKey child(int i) const {
    return {level + 1, (x << 1) | ((i >> 2) & 1), (y << 1) | ((i >> 1) & 1), (z << 1) | (i & 1)};
  }
  NodeKey parent() const { return {level - 1, x >> 1, y >> 1, z >> 1}; }
  int childIndex() const { return static_cast<int>(((x & 1) << 2) | ((y & 1) << 1) | (z & 1)); }
  // The ancestor at `lvl` (lvl <= level).
  NodeKey ancestor(uint32_t lvl) const {
    uint32_t s = level - lvl;
    return {lvl, x >> s, y >> s, z >> s};
  }
  bool isAncestorOf(const NodeKey& o) const {
    return o.level >= level && o.ancestor(level) == *this;
  }
  std::string name() const;
  static std::optional<NodeKey> parse(std::string_view name);

  bool operator==(const NodeKey&) const = default;
  // Breadth-first order: level, then Morton order within a level.
  bool operator<(const NodeKey& o) const;
};

struct NodeKeyHash {
  size_t operator()(const NodeKey& k) const {
    uint64_t h = (uint64_t(k.level) << 58) ^ (uint64_t(k.x) * 0x9E3779B97F4A7C15ull) ^
                 (uint64_t(k.y) * 0xC2B2AE3D27D4EB4Full) ^ (uint64_t(k.z) * 0x165667B19E3779F9ull);
    return static_cast<size_t>(h ^ (h >> 29));
  }
};

// Interleaves the low 21 bits of x, y, z (x highest), for sorting points within a node.
uint64_t mortonEncode21(uint32_t x, uint32_t y, uint32_t z);

}  // namespace nestlight
