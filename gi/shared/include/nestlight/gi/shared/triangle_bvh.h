// A bounding-volume hierarchy over meshes' triangles for rays on the GPU (ibl's visibility,
// shaders/gi/ibl/ibl_visibility.glsl; diffrender's exact query): built by Embree's own SAH builder
// (rtcBuildBVH, which hands each node to callbacks), flattened into the binary layout of
// shaders/gi/shared/triangle_bvh_interface.glsl.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "nestlight/frame/interface.h"

namespace nestlight::gi {

namespace glsl {
using vec4 = glm::vec4;
#include "gi/shared/triangle_bvh_interface.glsl"
}  // namespace glsl

using BvhNode = glsl::TriBvhNode;
using BvhTriangle = glsl::TriBvhTriangle;
static_assert(sizeof(BvhNode) == 32, "TriBvhNode must keep std430's layout");
static_assert(sizeof(BvhTriangle) == 48, "TriBvhTriangle must keep std430's layout");

struct TriangleBvh {
  std::vector<BvhNode> nodes;          // root first; empty without triangles
  std::vector<BvhTriangle> triangles;  // in leaf order
  int depth = 0;
  uint64_t degenerate = 0;  // zero-area or non-finite triangles left out
};

// `positions`: three corners per triangle, in the frame rays will be traced in.
TriangleBvh buildTriangleBvh(const std::vector<glm::vec3>& positions);

// The nearest hit along o + t d for t in (tMin, tMax) by the same traversal the shader runs
// (tests compare it with brute force); < 0 when nothing is hit.
float traceTriangleBvh(const TriangleBvh& bvh, const glm::vec3& o, const glm::vec3& d, float tMin,
                       float tMax);

}  // namespace nestlight::gi
