// The paged hierarchy (after Potree 2's hierarchy chunks).
//
// Nodes are grouped into chunks of `step` levels. A chunk lists its nodes breadth-first, one
// 32-byte entry each; the nodes `step` levels below the chunk's root appear as proxies whose
// offset and size locate their own chunk in hierarchy.bin. The root chunk comes first in the
// file. With step 3 a chunk holds at most 1 + 8 + 64 nodes and 512 proxies, 18,720 bytes: opening
// any scan reads metadata.json and at most that much of the hierarchy.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "nestlight/octree/codec.h"
#include "nestlight/octree/node_key.h"

namespace nestlight {

enum class NodeType : uint8_t { Inner = 0, Leaf = 1, Proxy = 2 };

// On disk, little endian: u8 type, u8 childMask, u8 codec, u8 spacingCode, u32 numPoints,
// u64 byteOffset, u64 byteSize, u64 checksum (XXH3-64 of the payload bytes, or of the child
// chunk for a proxy). Format version 1 wrote 0 for spacingCode (unknown).
struct HierarchyEntry {
  NodeType type = NodeType::Leaf;
  uint8_t childMask = 0;
  Codec codec = Codec::Raw;
  uint32_t numPoints = 0;
  uint64_t byteOffset = 0;
  uint64_t byteSize = 0;
  uint64_t checksum = 0;
  uint8_t spacingCode = 0;  // see encodeSpacing(); 0: not measured
};
inline constexpr size_t kHierarchyEntryBytes = 32;
inline constexpr uint32_t kHierarchyStep = 3;

// A node as the builder knows it: where its payload is.
struct NodeRecord {
  NodeKey key;
  Codec codec = Codec::Raw;
  uint32_t numPoints = 0;
  uint64_t byteOffset = 0;
  uint64_t byteSize = 0;
  uint64_t checksum = 0;
  uint8_t spacingCode = 0;  // see encodeSpacing()
};

// A node's measured point spacing, in one byte: the spacing (medianNeighbourSpacing, spacing.h)
// of the points drawn where this node is the finest drawn node (the node's own points and its
// ancestors' points inside its cube), relative to the nominal spacing of its
// level, in steps of 2^(1/16) (4.4%): code = 128 + round(16 log2(measured / nominal)), clamped to
// [1, 255], so ratios from 1/245 to 245 are kept. 0 means not measured.
uint8_t encodeSpacing(double measured, double nominal);
// The measured spacing in the units of `nominal`; 0 when `code` is 0.
double decodeSpacing(uint8_t code, double nominal);

struct HierarchyBlob {
  std::vector<uint8_t> bytes;
  uint64_t rootChunkSize = 0;
  uint64_t rootChunkChecksum = 0;
};

// Builds hierarchy.bin from every node of the octree. Every node's parent must be present.
HierarchyBlob buildHierarchy(std::vector<NodeRecord> nodes, uint32_t step = kHierarchyStep);

// Parses one chunk whose first entry is `chunkRoot`; appends (key, entry) in file order.
// Returns an empty string on success, else the reason (the input is untrusted).
std::string parseHierarchyChunk(const uint8_t* data, size_t size, const NodeKey& chunkRoot,
                                uint32_t step,
                                std::vector<std::pair<NodeKey, HierarchyEntry>>& out);

}  // namespace nestlight
