// A bounding-volume hierarchy over the inserted meshes' triangles for visibility rays on the GPU
// (shaders/gi/ibl/ibl_visibility.glsl): built by Embree's own SAH builder (rtcBuildBVH, which
// hands each node to callbacks), flattened into the binary layout of ibl_interface.glsl.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "nestlight/frame/interface.h"

namespace nestlight::gi::ibl {

namespace glsl {
using vec4 = glm::vec4;
#include "gi/ibl/ibl_interface.glsl"
}  // namespace glsl

using BvhNode = glsl::IblBvhNode;
using BvhTriangle = glsl::IblTriangle;
static_assert(sizeof(BvhNode) == 32, "IblBvhNode must keep std430's layout");
static_assert(sizeof(BvhTriangle) == 48, "IblTriangle must keep std430's layout");

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

}  // namespace nestlight::gi::ibl
