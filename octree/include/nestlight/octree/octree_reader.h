// Reads an octree folder written by OctreeWriter. Opening reads metadata.json and the root
// hierarchy chunk only; deeper chunks are read when a node below them is asked for. Node reads
// are thread-safe (pread) and verify the payload checksum.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <vector>

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
  // Every node, breadth first (reads the whole hierarchy).
  std::vector<std::pair<NodeKey, HierarchyEntry>> allNodes();

  // Reads, checks and decodes a node; positions come back in the octree's global integer grid.
  // Throws nestlight::Error on a checksum mismatch or undecodable payload.
  PointBuffer readNode(const NodeKey& key);
  // The raw payload bytes (for verify and benchmarks).
  std::vector<uint8_t> readPayload(const HierarchyEntry& e);

  uint64_t hierarchyBytesRead() const { return hierarchyBytesRead_; }

 private:
  void loadChunk(const NodeKey& root, uint64_t offset, uint64_t size, uint64_t checksum);

  std::filesystem::path dir_;
  Metadata meta_;
  int payloadFd_ = -1;
  int hierarchyFd_ = -1;
  std::mutex mutex_;
  std::unordered_map<NodeKey, HierarchyEntry, NodeKeyHash> entries_;  // proxies until loaded
  uint64_t hierarchyBytesRead_ = 0;
  std::unordered_set<uint64_t> loadedChunks_;  // offsets of the hierarchy chunks read
};

}  // namespace nestlight
