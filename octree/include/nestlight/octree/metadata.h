// metadata.json: everything a reader needs before touching the hierarchy. See docs/FORMAT.md.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "nestlight/octree/attribute.h"
#include "nestlight/octree/codec.h"
#include "nestlight/octree/geometry.h"

namespace nestlight {

// Version 2 stores each node's measured point spacing in its hierarchy entry (byte 3, which
// version 1 wrote as 0). Readers open versions 1 and 2; a version 1 octree has no measured
// spacing and viewers fall back to the nominal spacing of each level.
inline constexpr int kFormatVersion = 2;
inline constexpr int kOldestReadableVersion = 1;

// Every input point is kept, merged as an exact duplicate, or rejected with a reason:
// input == kept + duplicatesMerged + sum(rejected).
struct Accounting {
  uint64_t input = 0;
  uint64_t kept = 0;
  uint64_t duplicatesMerged = 0;
  std::map<std::string, uint64_t> rejected;  // reason -> count

  uint64_t rejectedTotal() const {
    uint64_t s = 0;
    for (auto& [k, v] : rejected) s += v;
    return s;
  }
  bool balanced() const { return input == kept + duplicatesMerged + rejectedTotal(); }
  void add(const Accounting& o);
};

// Rejection reasons used by the builder.
namespace reject {
inline constexpr const char* kNonFinite = "non_finite_coordinate";
inline constexpr const char* kOutsideBounds = "outside_declared_bounds";
inline constexpr const char* kUnreadable = "unreadable_source_data";  // damaged compressed chunks
}  // namespace reject

struct SourceRecord {
  std::string path;
  std::string format;
  uint64_t points = 0;                     // points read from this source
  uint64_t unreadable = 0;                 // declared points it could not decode (lenient LAZ)
  std::optional<uint64_t> declaredPoints;  // what its header claimed
  std::vector<std::string> warnings;
  nlohmann::json details;
};

// A per-point attribute layer stored beside the payloads, never inside them (DESIGN.md: HDR
// colour never overwrites the scan's LDR colour). `file` holds one checksummed payload per node
// and, at `indexOffset`, the index of those payloads (colour_layer.h; docs/FORMAT.md).
struct LayerRecord {
  std::string name;      // "hdr"
  std::string kind;      // "colour": linear RGB
  std::string encoding;  // "half_rgb_zstd": 3 half floats per point, zstd per node
  std::string file;
  uint64_t bytes = 0;  // the file's size
  uint64_t indexOffset = 0, indexBytes = 0, indexChecksum = 0;
  uint64_t nodes = 0, points = 0;
  double scale = 1;      // linear value = stored half * scale (keeps values beyond 65504)
  nlohmann::json build;  // how it was made: parameters, statistics, timings
};

struct Metadata {
  int version = kFormatVersion;
  std::string generator;
  Box3d bounds;  // tight bounds of the stored points (world units)
  Vec3d offset;  // world position of integer coordinate 0 (the root cube's min corner)
  // World units per integer step of each axis: a LAS file's own per-axis scales survive the
  // octree and every export (the integer cube is a cube; in world units a box when they differ).
  Vec3d scale{0.001, 0.001, 0.001};
  // The LAS offset of the inputs (the first one's): exports write it back, so that a LAS file's
  // integer coordinates come out as they went in. Absent for inputs without one.
  std::optional<Vec3d> sourceOffset;
  uint32_t cubeSize = 1;  // root cube edge in integer units, a power of two
  uint32_t depth = 0;     // deepest level that holds points
  double spacing = 0;     // nominal sample spacing of the root (world units); level l: /2^l
  uint64_t points = 0;    // points stored
  uint64_t nodes = 0;
  PointLayout layout;     // attributes besides position
  int rgbSourceBits = 0;  // 8 when every source gave 8-bit colour, 16 otherwise, 0 without rgb
  bool normalsEstimated = false;
  nlohmann::json normalEstimation;  // parameters when estimated
  Accounting accounting;
  nlohmann::json crs;
  std::vector<SourceRecord> sources;
  nlohmann::json build;  // parameters and timings of the conversion

  std::string payloadFile = "octree.bin";
  uint64_t payloadBytes = 0;
  std::string hierarchyFile = "hierarchy.bin";
  uint32_t hierarchyStep = 3;
  uint64_t hierarchyBytes = 0;
  uint64_t rootChunkSize = 0;
  uint64_t rootChunkChecksum = 0;

  std::vector<LayerRecord> layers;

  // The layer named `name`, or nullptr.
  const LayerRecord* layer(std::string_view name) const {
    for (const auto& l : layers)
      if (l.name == name) return &l;
    return nullptr;
  }

  // The largest axis step, and the root cube's largest world edge (LOD and camera distances).
  double maxScale() const { return std::max({scale.x, scale.y, scale.z}); }
  double cubeWorldSize() const { return cubeSize * maxScale(); }
  // World position of integer coordinate `q` on axis `a`.
  double world(int a, double q) const { return offset[a] + q * scale[a]; }
  // World position of the integer coordinates q[0..2] (a PointBuffer's pos + 3 * i).
  Vec3d worldPoint(const uint32_t* q) const {
    return {world(0, q[0]), world(1, q[1]), world(2, q[2])};
  }
  // The nominal sample spacing of a level: the root's `spacing` halved per level.
  double levelSpacing(uint32_t level) const {
    return std::ldexp(spacing, -static_cast<int>(level));
  }
  // World bounds of a node's cube.
  Box3d nodeBounds(uint32_t level, uint32_t x, uint32_t y, uint32_t z) const;

  nlohmann::json toJson() const;
  // Throws nestlight::Error naming `file` and the field.
  static Metadata fromJson(const nlohmann::json& j, const std::string& file);
};

}  // namespace nestlight
