// Paged hierarchy, after Potree 2 (Schütz, Ohrhallinger, Wimmer 2020, section 4.3): nodes are
// stored in chunks of a few levels so that a viewer reads only the part of the tree it opens.
#include "nestlight/octree/hierarchy.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <deque>
#include <unordered_map>

#include "nestlight/octree/checksum.h"
#include "nestlight/octree/error.h"

namespace nestlight {
namespace {

void putEntry(uint8_t* p, const HierarchyEntry& e) {
  p[0] = static_cast<uint8_t>(e.type);
  p[1] = e.childMask;
  p[2] = static_cast<uint8_t>(e.codec);
  p[3] = e.spacingCode;
  std::memcpy(p + 4, &e.numPoints, 4);
  std::memcpy(p + 8, &e.byteOffset, 8);
  std::memcpy(p + 16, &e.byteSize, 8);
  std::memcpy(p + 24, &e.checksum, 8);
}

HierarchyEntry getEntry(const uint8_t* p) {
  HierarchyEntry e;
  e.type = static_cast<NodeType>(p[0]);
  e.childMask = p[1];
  e.codec = static_cast<Codec>(p[2]);
  e.spacingCode = p[3];
  std::memcpy(&e.numPoints, p + 4, 4);
  std::memcpy(&e.byteOffset, p + 8, 8);
  std::memcpy(&e.byteSize, p + 16, 8);
  std::memcpy(&e.checksum, p + 24, 8);
  return e;
}

struct BuildNode {
  NodeRecord rec;
  uint8_t childMask = 0;
};

}  // namespace

uint8_t encodeSpacing(double measured, double nominal) {
  if (!(measured > 0) || !(nominal > 0) || !std::isfinite(measured / nominal)) return 0;
  const double steps = std::round(16.0 * std::log2(measured / nominal));
  return static_cast<uint8_t>(std::clamp(128.0 + steps, 1.0, 255.0));
}

double decodeSpacing(uint8_t code, double nominal) {
  return code == 0 ? 0.0 : nominal * std::exp2((int(code) - 128) / 16.0);
}

HierarchyBlob buildHierarchy(std::vector<NodeRecord> nodes, uint32_t step) {
  NL_CHECK(step >= 1);
  std::unordered_map<NodeKey, BuildNode, NodeKeyHash> map;
  map.reserve(nodes.size() * 2);
  for (auto& r : nodes) map[r.key].rec = r;
  for (auto& [k, n] : map) {
    if (k.level == 0) continue;
    auto it = map.find(k.parent());
    NL_CHECK_MSG(it != map.end(), "node " + k.name() + " has no parent");
    it->second.childMask |= static_cast<uint8_t>(1u << k.childIndex());
  }
  NL_CHECK_MSG(map.count(NodeKey::root()), "octree has no root node");

  // The nodes of a chunk, breadth first; `proxies` collects nodes that root further chunks.
  auto chunkNodes = [&](const NodeKey& root, std::vector<NodeKey>* proxies) {
    std::vector<NodeKey> list;
    std::deque<NodeKey> queue{root};
    while (!queue.empty()) {
      NodeKey k = queue.front();
      queue.pop_front();
      list.push_back(k);
      const BuildNode& n = map.at(k);
      if (k.level - root.level == step) {
        if (n.childMask) proxies->push_back(k);
        continue;
      }
      for (int i = 0; i < 8; ++i)
        if (n.childMask & (1u << i)) queue.push_back(k.child(i));
    }
    return list;
  };

  // Pass 1: chunk order (breadth first over chunk roots) and sizes.
  struct Chunk {
    NodeKey root;
    std::vector<NodeKey> nodes;
    uint64_t offset = 0;
  };
  std::vector<Chunk> chunks;
  std::unordered_map<NodeKey, size_t, NodeKeyHash> chunkOf;
  std::deque<NodeKey> roots{NodeKey::root()};
  uint64_t offset = 0;
  while (!roots.empty()) {
    NodeKey r = roots.front();
    roots.pop_front();
    std::vector<NodeKey> proxies;
    Chunk c{r, chunkNodes(r, &proxies), offset};
    offset += c.nodes.size() * kHierarchyEntryBytes;
    chunkOf[r] = chunks.size();
    chunks.push_back(std::move(c));
    for (auto& p : proxies) roots.push_back(p);
  }

  // Pass 2: entries; deepest chunks first so that a proxy can carry its chunk's checksum.
  HierarchyBlob blob;
  blob.bytes.resize(offset);
  std::vector<uint64_t> chunkChecksum(chunks.size());
  for (size_t ci = chunks.size(); ci-- > 0;) {
    const Chunk& c = chunks[ci];
    for (size_t i = 0; i < c.nodes.size(); ++i) {
      const NodeKey& k = c.nodes[i];
      const BuildNode& n = map.at(k);
      HierarchyEntry e;
      e.childMask = n.childMask;
      e.numPoints = n.rec.numPoints;
      e.codec = n.rec.codec;
      e.spacingCode = n.rec.spacingCode;
      bool proxy = k.level - c.root.level == step && n.childMask;
      if (proxy) {
        size_t sub = chunkOf.at(k);
        e.type = NodeType::Proxy;
        e.byteOffset = chunks[sub].offset;
        e.byteSize = chunks[sub].nodes.size() * kHierarchyEntryBytes;
        e.checksum = chunkChecksum[sub];
      } else {
        e.type = n.childMask ? NodeType::Inner : NodeType::Leaf;
        e.byteOffset = n.rec.byteOffset;
        e.byteSize = n.rec.byteSize;
        e.checksum = n.rec.checksum;
      }
      putEntry(&blob.bytes[c.offset + i * kHierarchyEntryBytes], e);
    }
    chunkChecksum[ci] = checksum64(&blob.bytes[c.offset], c.nodes.size() * kHierarchyEntryBytes);
  }
  blob.rootChunkSize = chunks[0].nodes.size() * kHierarchyEntryBytes;
  blob.rootChunkChecksum = chunkChecksum[0];
  return blob;
}

std::string parseHierarchyChunk(const uint8_t* data, size_t size, const NodeKey& chunkRoot,
                                uint32_t step,
                                std::vector<std::pair<NodeKey, HierarchyEntry>>& out) {
  if (size == 0 || size % kHierarchyEntryBytes != 0)
    return "hierarchy chunk size " + std::to_string(size) + " is not a multiple of 32";
  if (step == 0 || step > 8) return "hierarchy step out of range";
  const size_t count = size / kHierarchyEntryBytes;
  std::deque<NodeKey> queue{chunkRoot};
  size_t i = 0;
  for (; i < count; ++i) {
    if (queue.empty()) return "hierarchy chunk has more entries than its child masks describe";
    NodeKey k = queue.front();
    queue.pop_front();
    HierarchyEntry e = getEntry(data + i * kHierarchyEntryBytes);
    if (static_cast<uint8_t>(e.type) > 2 || static_cast<uint8_t>(e.codec) > 2)
      return "hierarchy entry " + std::to_string(i) + " has an unknown type or codec";
    const uint32_t depth = k.level - chunkRoot.level;
    if (e.type == NodeType::Proxy && depth != step)
      return "hierarchy entry " + std::to_string(i) + " is a proxy above the chunk's last level";
    if (depth == step && e.childMask && e.type != NodeType::Proxy)
      return "hierarchy entry " + std::to_string(i) + " should be a proxy";
    if (e.type == NodeType::Leaf && e.childMask)
      return "hierarchy entry " + std::to_string(i) + " is a leaf with children";
    if (k.level >= 31 && e.childMask) return "hierarchy deeper than 31 levels";
    if (depth < step)
      for (int c = 0; c < 8; ++c)
        if (e.childMask & (1u << c)) queue.push_back(k.child(c));
    out.emplace_back(k, e);
  }
  if (!queue.empty()) return "hierarchy chunk ends before its child masks are satisfied";
  return {};
}

}  // namespace nestlight
