// Writes an octree folder. Payloads go to octree.bin in one large file; hierarchy.bin and
// metadata.json are written by finish(). Every file is written under a temporary name and
// renamed, metadata.json last: a killed conversion leaves no metadata.json, so nothing that
// `verify` or a reader accepts.
#pragma once

#include <cstdint>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

#include "nestlight/octree/hierarchy.h"
#include "nestlight/octree/metadata.h"
#include "nestlight/octree/point_buffer.h"

namespace nestlight {

// Whether an entry of an octree folder is one of the octree's own files (metadata, hierarchy,
// payload, attribute layers, the temporary files of a build or of HDR expansion): what replacing
// the octree may discard. Anything else in the folder is the user's.
bool isOctreeFileName(const std::string& name);

class OctreeWriter {
 public:
  // Creates `dir` (it must not hold an octree unless `overwrite`).
  OctreeWriter(std::filesystem::path dir, PointLayout layout, Codec codec, bool overwrite);
  ~OctreeWriter();

  // Encodes and appends one node. `points.pos` holds positions relative to the node's cube min
  // corner and should be in Morton order. `spacingCode` is the node's measured spacing
  // (encodeSpacing; 0: not measured). Thread-safe; encoding runs on the calling thread.
  void writeNode(const NodeKey& key, const PointBuffer& points, uint8_t spacingCode = 0);

  // Writes the hierarchy and `meta` (payload, hierarchy and node fields are filled here).
  void finish(Metadata& meta);

  // A part of an octree built by several processes (convert --mpi): closes the payload (left in
  // dir/octree.bin.tmp, synced) and returns the nodes written, their offsets within it.
  std::vector<NodeRecord> finishPart();
  // The octree in `dir` whose payload the parts were assembled into (dir/octree.bin.tmp,
  // `payloadBytes`, synced), with every part's nodes at their offsets there: as finish().
  static void finishAssembled(const std::filesystem::path& dir, Metadata& meta,
                              std::vector<NodeRecord> nodes, uint64_t payloadBytes);

  uint64_t bytesWritten() const { return offset_; }
  size_t nodeCount() const { return nodes_.size(); }

 private:
  std::filesystem::path dir_;
  PointLayout layout_;
  Codec codec_;
  int fd_ = -1;
  std::mutex mutex_;
  uint64_t offset_ = 0;
  std::vector<NodeRecord> nodes_;
  bool finished_ = false;
};

// Writes `bytes` to `path` atomically (temporary file, fsync, rename).
void writeFileAtomic(const std::filesystem::path& path, const void* bytes, size_t size);

}  // namespace nestlight
