// `nestlight export --format potree`: writes an octree as a Potree 2.0 dataset (metadata.json,
// hierarchy.bin, octree.bin), the format PotreeConverter 2 writes and the Potree web viewer
// (1.8 and later) opens. See docs/POTREE_EXPORT.md.
//
// Nothing is resampled: Potree's node names and child numbering are ours (child i has octant bits
// i = (x << 2) | (y << 1) | z in both), so every node keeps its name and exactly its stored points,
// in their stored order. Positions keep our integer grid: Potree's offset and scale are the
// octree's, and its bounding box is our root cube, so each Potree node box is our node's cube.
// The export streams node by node: memory holds one hierarchy chunk's entries and a few nodes'
// points at a time, never the whole octree.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "nestlight/converters/progress.h"

namespace nestlight {

struct PotreeExportOptions {
  // Hierarchy levels per chunk of hierarchy.bin: a chunk rooted at level L lists its nodes down
  // to level L + stepSize, where nodes that have children become proxies of their own chunk.
  // PotreeConverter 2 uses 4.
  uint32_t stepSize = 4;
  // Write into an existing directory that is not empty (replacing metadata.json, hierarchy.bin
  // and octree.bin there; other files are left alone).
  bool overwrite = false;
  ProgressMode progress = ProgressMode::Auto;
  std::string name;      // metadata "name"; empty: the octree folder's name
  unsigned threads = 0;  // nodes decoded in parallel; 0: all cores
};

// How one of our attributes became Potree attributes (for reports and the docs).
struct PotreeAttributeMapping {
  std::string source;               // our name ("gps_time", "normal", layer "hdr")
  std::vector<std::string> potree;  // Potree name(s) ("gps-time"; "NormalX", "NormalY", "NormalZ")
  std::string type;                 // Potree type ("double", "uint16", ...)
  std::string note;                 // conversion, when the bytes are not copied unchanged
};

struct PotreeExportReport {
  uint64_t points = 0;
  uint64_t nodes = 0;
  uint64_t proxies = 0;
  uint64_t chunks = 0;
  uint64_t octreeBytes = 0;
  uint64_t hierarchyBytes = 0;
  uint64_t rgbLifted = 0;  // colour components raised from 1..255 to 256 (see the .cpp)
  std::vector<PotreeAttributeMapping> attributes;
};

// Writes the octree at `octreeDir` into the directory `outDir` (created when absent). Throws
// nestlight::Error when `outDir` is a file, is the octree itself, or is a non-empty directory
// without `options.overwrite`, and on unreadable input. A run that fails leaves no metadata.json.
PotreeExportReport exportPotree(const std::filesystem::path& octreeDir,
                                const std::filesystem::path& outDir,
                                const PotreeExportOptions& options = {});

}  // namespace nestlight
