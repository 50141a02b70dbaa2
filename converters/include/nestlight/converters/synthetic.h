// A seeded synthetic point source, after PDAL's "faux" reader: scenes of any size for tests,
// benchmarks, `nestlight generate` and the demo, without shipping data.
//
// Point i is a pure function of (seed, i), so any batch size, and rewind(), gives the same points.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "nestlight/converters/reader.h"
#include "nestlight/octree/geometry.h"

namespace nestlight {

enum class SyntheticShape {
  Surfaces,    // a scanned-building-like scene: ground, box buildings, a dome, a ball, columns
  Cube,        // uniform in the filled cube [origin, origin + size]^3
  Duplicates,  // every point the same: origin + size/2, same attributes
  Plane,       // uniform on the square [origin, origin + size]^2 at z = origin.z exactly
  Room,        // a closed Cornell-box-like room [0, size]^3: red wall at x = 0, green at x = size,
               // white elsewhere, a bright ceiling patch, a tall and a short white block;
               // normals face into the room
  Nave,        // a church nave: floor, walls and ceiling of a hall 2 x 1 x 0.6 (times size / 2),
               // two rows of columns, an apse dome at the east end; normals face inwards
};

struct SyntheticSpec {
  SyntheticShape shape = SyntheticShape::Surfaces;
  uint64_t points = 1'000'000;
  uint64_t seed = 1;
  Vec3d origin{0, 0, 0};  // added to every point: national-grid tests use {500000, 5000000, 100}
  double size = 100.0;    // extent in metres
  double noise = 0.002;   // surface noise (m, standard deviation; Surfaces only)
  bool rgb = true, intensity = true, normals = false;
  double precision = 0.001;  // coordinates are origin + k * precision; <= 0: not quantised
};

// A PointReader: header().format == "synthetic", declaredPoints == points, declaredBounds hold
// every point exactly. Layout, in order of the flags: "rgb" uint16 x3 (8-bit values * 257,
// rgbBits 8), "intensity" uint16, "normal" float x3 (unit length).
std::unique_ptr<PointReader> openSynthetic(const SyntheticSpec& spec);
// Writes openSynthetic(spec) to `path` (any format createWriter takes, by its extension), quantised
// to spec.precision about spec.origin; returns the number of points.
uint64_t writeSynthetic(const SyntheticSpec& spec, const std::string& path);

// "surfaces", "cube", "duplicates", "plane" (case-insensitive).
std::optional<SyntheticShape> parseSyntheticShape(std::string_view name);
const char* syntheticShapeName(SyntheticShape shape);

}  // namespace nestlight
