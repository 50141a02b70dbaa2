// `nestlight export` and `info --clip`: the points of an octree (all, one level, or those a set of
// clipping volumes keeps) written to LAS, LAZ or PLY, or counted.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>

#include "nestlight/converters/reader.h"
#include "nestlight/octree/clip_volume.h"
#include "nestlight/octree/hierarchy.h"
#include "nestlight/octree/node_key.h"

namespace nestlight {

class Progress;

struct ExportOptions {
  std::optional<uint32_t> level;  // only this level's nodes
  const ClipSet* clip = nullptr;  // only the points it keeps (tested in world coordinates)
  Progress* progress = nullptr;   // a "read" phase in points
  unsigned threads = 0;           // nodes decoded and clipped in parallel (0: all cores)
};

struct ExportReport {
  uint64_t points = 0;        // written (or counted)
  uint64_t nodes = 0;         // nodes whose points were looked at
  uint64_t nodesWhole = 0;    // of those, kept whole: no point tested (or, counting, not read)
  uint64_t nodesSkipped = 0;  // nodes outside the clipping volumes, never read
  uint64_t pointsTested = 0;  // points tested one by one
  uint64_t pointsRead = 0;    // points decoded
  uint64_t payloadBytes = 0;  // compressed node payloads read
};

// Positions are offset + integer * scale, so a LAS file written with the octree's scale and
// offset holds exactly the stored integers. Nodes are read one at a time per thread and in the
// hierarchy's order, so memory is bounded by a few nodes whatever the octree's size.
ExportReport exportOctree(const std::filesystem::path& dir, const std::filesystem::path& file,
                          const ExportOptions& options);
uint64_t exportOctree(const std::filesystem::path& dir, const std::filesystem::path& file,
                      std::optional<uint32_t> level = std::nullopt);

// The points `options` selects, counted: nodes the volumes keep whole are counted from the
// hierarchy without reading them.
ExportReport countOctree(const std::filesystem::path& dir, const ExportOptions& options);

// What a walk with `options` would read, from the hierarchy alone (no payload read): nodes,
// nodesWhole, nodesSkipped, pointsRead (the points in the nodes read) and payloadBytes.
ExportReport selectOctree(const std::filesystem::path& dir, const ExportOptions& options);

// The walk behind both, for other consumers (profiles). Each selected node is read and clipped
// on a worker thread: its points' world coordinates (xyz) and attributes go into `batch`, kept
// points only, and `parallel` (optional) may add to it there; then `serial` receives the nodes
// one at a time, in the hierarchy's breadth-first order, whatever the threads.
struct ClippedNode {
  NodeKey key;
  HierarchyEntry entry;
  bool whole = false;  // inside the clipping volumes whole: no point was tested
  PointBatch batch;
  std::vector<double> extra;  // for the consumer's own per-point values
};
ExportReport walkClipped(const std::filesystem::path& dir, const ExportOptions& options,
                         const std::function<void(ClippedNode&)>& parallel,
                         const std::function<void(ClippedNode&)>& serial);

}  // namespace nestlight
