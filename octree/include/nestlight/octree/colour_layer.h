// Colour layers: a linear RGB colour per point (the HDR colour that HDR expansion computes),
// stored in a file of its own beside the payloads so that the scan's recorded colour is never
// overwritten (DESIGN.md).
//
// A layer file holds one payload per node (the node's points in the order its octree payload
// decodes them: 3 half floats each, channel-planar and byte-shuffled, then zstd) followed by an
// index of 40-byte entries, one per node in breadth-first key order (docs/FORMAT.md). The file is
// written under a temporary name, fsynced, renamed to a name no other version of the layer has,
// and only then recorded in metadata.json, itself replaced atomically: a run killed at any point
// leaves either the previous layer or the new one whole, never a mixture, and the octree valid.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "nestlight/octree/metadata.h"
#include "nestlight/octree/node_key.h"

namespace nestlight {

inline constexpr size_t kLayerIndexEntryBytes = 40;
// The largest finite half float: stored values are clamped to it (after dividing by the scale).
inline constexpr float kHalfMax = 65504.0f;

struct LayerIndexEntry {
  NodeKey key;
  uint32_t points = 0;
  uint32_t byteSize = 0;
  uint64_t byteOffset = 0;
  uint64_t checksum = 0;
};

// Encodes one node's colours (3 floats per point, linear) as stored; `scale` divides them first.
// Negative and non-finite values become 0 and values beyond half range clamp: `clamped` counts
// the channels changed.
std::vector<uint8_t> encodeColourPayload(const float* rgb, size_t points, double scale,
                                         uint64_t& clamped);
// Decodes exactly `points` colours (times `scale`) into `rgb`. Untrusted bytes: returns an empty
// string on success, else the reason; never reads out of bounds (fuzzed).
std::string decodeColourPayload(const uint8_t* data, size_t size, size_t points, double scale,
                                std::vector<float>& rgb);
// Parses an index; the input is untrusted. Returns an empty string on success, else the reason.
std::string parseLayerIndex(const uint8_t* data, size_t size, std::vector<LayerIndexEntry>& out);

// Throws nestlight::Error when `name` cannot name a colour layer: empty, with '/' or '.', or
// "rgb", which scene files read as the scan's recorded colour ("colour": "rgb").
void checkLayerName(const std::string& name);

class ColourLayerWriter {
 public:
  // Starts a new version of layer `name` in the octree at `dir` (its metadata.json must exist).
  // Stored values are linear / scale (choose scale >= max value / 65504 to keep the range).
  ColourLayerWriter(std::filesystem::path dir, std::string name, double scale);
  ~ColourLayerWriter();
  ColourLayerWriter(const ColourLayerWriter&) = delete;
  ColourLayerWriter& operator=(const ColourLayerWriter&) = delete;

  // Thread-safe; encoding runs on the calling thread. Each node once.
  void writeNode(const NodeKey& key, const float* rgb, size_t points);

  // Checks that every node of the octree was written with its point count, writes the index,
  // renames the file into place and records the layer (replacing an older version, whose file
  // is then deleted) in metadata.json atomically. Throws nestlight::Error when nodes are missing.
  LayerRecord finish(const nlohmann::json& build);

  uint64_t clampedValues() const { return clamped_.load(); }

 private:
  std::filesystem::path dir_, tmp_;
  std::string name_;
  double scale_;
  int fd_ = -1;
  std::mutex mutex_;
  uint64_t offset_ = 0;
  std::vector<LayerIndexEntry> entries_;
  std::atomic<uint64_t> clamped_{0};
  bool finished_ = false;
};

// Reads a colour layer. Opening reads and checks its index; node reads are thread-safe (pread)
// and check the payload's checksum.
class ColourLayerReader {
 public:
  // Throws nestlight::Error naming the file when the layer is absent or its index is damaged.
  ColourLayerReader(const std::filesystem::path& dir, const Metadata& meta, std::string_view name);
  ~ColourLayerReader();
  ColourLayerReader(const ColourLayerReader&) = delete;
  ColourLayerReader& operator=(const ColourLayerReader&) = delete;

  const LayerRecord& record() const { return record_; }
  const std::vector<LayerIndexEntry>& entries() const { return entries_; }
  const LayerIndexEntry* find(const NodeKey& key) const;
  // The node's colours, 3 linear floats per point. Throws nestlight::Error (file, byte) when the
  // node is missing, its point count is not `expectedPoints`, or its payload is damaged.
  std::vector<float> readNode(const NodeKey& key, uint32_t expectedPoints) const;

 private:
  std::filesystem::path path_;
  LayerRecord record_;
  int fd_ = -1;
  std::vector<LayerIndexEntry> entries_;
  std::unordered_map<NodeKey, size_t, NodeKeyHash> byKey_;
};

// Deletes what killed layer writes left in `dir` (temporary files, layer files that
// metadata.json does not name, HDR expansion's "*.expand.scratch"); returns their names.
std::vector<std::string> removeOrphanLayerFiles(const std::filesystem::path& dir,
                                                const Metadata& meta);
// The same, without deleting: what verify reports.
std::vector<std::string> orphanLayerFiles(const std::filesystem::path& dir, const Metadata& meta);

}  // namespace nestlight
