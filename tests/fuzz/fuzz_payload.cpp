// libFuzzer target for the node payload decoders (raw, zstd, draco) and the hierarchy chunk
// parser. Input: byte 0 picks the decoder and layout, bytes 1-2 the point count, the rest is the
// payload. Decoders must return an error, never crash or read out of bounds.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "nestlight/octree/codec.h"
#include "nestlight/octree/hierarchy.h"

using namespace nestlight;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 3) return 0;
  const uint8_t sel = data[0];
  const size_t count = size_t(data[1]) | size_t(data[2]) << 8;
  const uint8_t* payload = data + 3;
  const size_t n = size - 3;
  if ((sel & 3) == 3) {
    std::vector<std::pair<NodeKey, HierarchyEntry>> out;
    parseHierarchyChunk(payload, n, NodeKey::root(), 1 + (sel >> 2) % 4, out);
    return 0;
  }
  PointLayout layout;
  if (sel & 4) layout.add({"rgb", ScalarType::U16, 3, ""});
  if (sel & 8) layout.add({"normal", ScalarType::F32, 3, ""});
  if (sel & 16) layout.add({"gps_time", ScalarType::F64, 1, ""});
  PointBuffer out;
  const Codec codec = static_cast<Codec>(sel & 3);
  decodePayload(codec, layout, payload, n, count, out);
  // Round trip: whatever decodes must encode and decode to the same points.
  if (out.size() == count && count > 0) {
    std::vector<uint8_t> again = encodePayload(codec, layout, out);
    PointBuffer back;
    if (!decodePayload(codec, layout, again.data(), again.size(), count, back).empty())
      __builtin_trap();
    if (codec != Codec::Draco && (back.pos != out.pos || back.attrs != out.attrs)) __builtin_trap();
  }
  return 0;
}
