// The box-against-frustum test shared by Frustum::intersects and cut selection.
#pragma once

#include <cmath>
#include <cstdint>

#include "nestlight/streaming/view.h"

namespace nestlight::streaming::detail {

inline constexpr uint8_t kAllPlanes = 0x3F;

// False when the box (center c, half extents h) lies wholly outside a plane of `mask`. Clears the
// bits of planes the box lies wholly inside: a child box needs no test against them (the
// hierarchical culling of scene graphs), which spares most tests deep in the octree.
inline bool boxInFrustum(const Frustum& f, const double c[3], const double h[3], uint8_t& mask) {
  for (int i = 0; i < 6; ++i) {
    if (!(mask & (1u << i))) continue;
    const glm::dvec4& p = f.planes[size_t(i)];
    const double s = p.x * c[0] + p.y * c[1] + p.z * c[2] + p.w;
    const double e = std::abs(p.x) * h[0] + std::abs(p.y) * h[1] + std::abs(p.z) * h[2];
    if (s + e < 0) return false;
    if (s - e >= 0) mask = static_cast<uint8_t>(mask & ~(1u << i));
  }
  return true;
}

}  // namespace nestlight::streaming::detail
