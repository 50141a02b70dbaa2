// Node payload codecs.
//
//  raw   positions (uint32 x3, node-relative) then attributes, point after point;
//  zstd  structure-of-arrays streams, delta-coded (zig-zag) integers, byte-shuffled, then zstd;
//        points are expected in Morton order within the node, which keeps deltas small;
//  draco Google Draco point-cloud encoding (kd-tree for integer attributes: lossless).
//
// Decoders take untrusted bytes (a damaged or hostile file) and return an error message instead
// of asserting or reading out of bounds; they are fuzzed (tests/fuzz/fuzz_payload.cpp).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "nestlight/octree/attribute.h"
#include "nestlight/octree/point_buffer.h"

namespace nestlight {

enum class Codec : uint8_t { Raw = 0, Zstd = 1, Draco = 2 };

const char* codecName(Codec c);
std::optional<Codec> parseCodecName(std::string_view name);

// `points.pos` holds node-relative coordinates.
std::vector<uint8_t> encodePayload(Codec codec, const PointLayout& layout,
                                   const PointBuffer& points);

// Decodes exactly `count` points into `out` (node-relative positions). Returns an empty string on
// success, else the reason.
std::string decodePayload(Codec codec, const PointLayout& layout, const uint8_t* data, size_t size,
                          size_t count, PointBuffer& out);

}  // namespace nestlight
