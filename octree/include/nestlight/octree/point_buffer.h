// Points in memory: integer positions in the octree's grid, plus packed attributes.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "nestlight/octree/attribute.h"

namespace nestlight {

struct PointBuffer {
  // 3 per point: integer coordinates relative to the octree offset, in units of the scale.
  std::vector<uint32_t> pos;
  // layout.stride() bytes per point, the layout being the octree's.
  std::vector<uint8_t> attrs;
  size_t stride = 0;

  PointBuffer() = default;
  explicit PointBuffer(size_t attributeStride) : stride(attributeStride) {}
  size_t size() const { return pos.size() / 3; }
  bool empty() const { return pos.empty(); }
  void clear() {
    pos.clear();
    attrs.clear();
  }
  void reserve(size_t n) {
    pos.reserve(n * 3);
    attrs.reserve(n * stride);
  }
  void push(const uint32_t* p, const uint8_t* a) {
    pos.insert(pos.end(), p, p + 3);
    attrs.insert(attrs.end(), a, a + stride);
  }
  void pushFrom(const PointBuffer& o, size_t i) {
    push(&o.pos[i * 3], o.attrs.data() + i * stride);
  }
  const uint8_t* attrsOf(size_t i) const { return attrs.data() + i * stride; }
  // Bytes in memory per point.
  size_t bytesPerPoint() const { return 12 + stride; }
};

}  // namespace nestlight
