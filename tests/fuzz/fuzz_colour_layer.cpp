// libFuzzer target for the colour layer's decoders (the HDR colour beside a scan's): the node
// payload decoder and the index parser. Input: byte 0 picks the decoder, bytes 1-2 the point
// count, the rest is the payload or index. Both must return an error, never crash or read out
// of bounds; what decodes must encode and decode to the same colours.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "nestlight/octree/colour_layer.h"

using namespace nestlight;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 3) return 0;
  const size_t count = size_t(data[1]) | size_t(data[2]) << 8;
  const uint8_t* bytes = data + 3;
  const size_t n = size - 3;
  if (data[0] & 1) {
    std::vector<LayerIndexEntry> entries;
    parseLayerIndex(bytes, n, entries);
    return 0;
  }
  std::vector<float> rgb;
  if (!decodeColourPayload(bytes, n, count, 1.0, rgb).empty()) return 0;
  if (rgb.size() != count * 3) __builtin_trap();
  // Stored values are finite or not (a hostile file may hold NaN bit patterns); the finite,
  // non-negative ones must survive a second round exactly (they are halves already).
  for (float& v : rgb)
    if (!std::isfinite(v) || v < 0) v = 0;
  uint64_t clamped = 0;
  const std::vector<uint8_t> again = encodeColourPayload(rgb.data(), count, 1.0, clamped);
  std::vector<float> back;
  if (!decodeColourPayload(again.data(), again.size(), count, 1.0, back).empty() || back != rgb)
    __builtin_trap();
  return 0;
}
