// Embree builds (rtcBuildBVH: its binned SAH builder, nodes made through callbacks into memory
// it owns for the build); this file only flattens the result depth first for the GPU.
#include "nestlight/gi/shared/triangle_bvh.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include "nestlight/octree/error.h"

namespace nestlight::gi {

namespace {

struct BvhBuildNode {
  virtual ~BvhBuildNode() = default;
};
struct BvhInnerNode final : BvhBuildNode {
  BvhBuildNode* child[2] = {nullptr, nullptr};
  RTCBounds bounds[2] = {};
};
struct BvhLeafNode final : BvhBuildNode {
  unsigned first = 0, count = 0;  // into the build's primitive order (prims[] by primID)
  unsigned ids[4] = {};
};

void* createNode(RTCThreadLocalAllocator alloc, unsigned int childCount, void*) {
  NL_CHECK(childCount == 2);
  return new (rtcThreadLocalAlloc(alloc, sizeof(BvhInnerNode), 16)) BvhInnerNode;
}
void setNodeChildren(void* node, void** children, unsigned int childCount, void*) {
  for (unsigned i = 0; i < childCount; ++i)
    static_cast<BvhInnerNode*>(node)->child[i] = static_cast<BvhBuildNode*>(children[i]);
}
void setNodeBounds(void* node, const RTCBounds** bounds, unsigned int childCount, void*) {
  for (unsigned i = 0; i < childCount; ++i)
    static_cast<BvhInnerNode*>(node)->bounds[i] = *bounds[i];
}
void* createLeaf(RTCThreadLocalAllocator alloc, const RTCBuildPrimitive* prims, size_t numPrims,
                 void*) {
  NL_CHECK(numPrims >= 1 && numPrims <= 4);
  auto* leaf = new (rtcThreadLocalAlloc(alloc, sizeof(BvhLeafNode), 16)) BvhLeafNode;
  leaf->count = unsigned(numPrims);
  for (size_t i = 0; i < numPrims; ++i) leaf->ids[i] = prims[i].primID;
  return leaf;
}

float bits(uint32_t u) {
  return std::bit_cast<float>(u);
}
uint32_t ubits(float f) {
  return std::bit_cast<uint32_t>(f);
}

struct Flattener {
  const std::vector<BvhTriangle>& source;
  TriangleBvh& out;
  // Writes `node` (whose box is lo..hi) at out.nodes[at] and its sub-tree after it.
  void write(const BvhBuildNode* node, size_t at, glm::vec3 lo, glm::vec3 hi, int depth) {
    out.depth = std::max(out.depth, depth);
    BvhNode& n = out.nodes[at];
    n.lo = glm::vec4(lo, 0.0f);
    n.hi = glm::vec4(hi, 0.0f);
    if (const auto* leaf = dynamic_cast<const BvhLeafNode*>(node)) {
      const uint32_t first = uint32_t(out.triangles.size());
      for (unsigned i = 0; i < leaf->count; ++i) out.triangles.push_back(source[leaf->ids[i]]);
      out.nodes[at].lo.w = bits(first | TRI_BVH_LEAF);
      out.nodes[at].hi.w = bits(leaf->count);
      return;
    }
    const auto* inner = static_cast<const BvhInnerNode*>(node);
    auto box = [](const RTCBounds& b, glm::vec3* l, glm::vec3* h) {
      *l = {b.lower_x, b.lower_y, b.lower_z};
      *h = {b.upper_x, b.upper_y, b.upper_z};
    };
    glm::vec3 l0, h0, l1, h1;
    box(inner->bounds[0], &l0, &h0);
    box(inner->bounds[1], &l1, &h1);
    const size_t left = out.nodes.size();
    out.nodes.emplace_back();
    write(inner->child[0], left, l0, h0, depth + 1);
    const size_t right = out.nodes.size();
    out.nodes.emplace_back();
    write(inner->child[1], right, l1, h1, depth + 1);
    out.nodes[at].lo.w = bits(uint32_t(left));
    out.nodes[at].hi.w = bits(uint32_t(right));
  }
};

}  // namespace

TriangleBvh buildTriangleBvh(const std::vector<glm::vec3>& positions) {
  NL_CHECK(positions.size() % 3 == 0);
  TriangleBvh out;
  std::vector<BvhTriangle> tris;
  std::vector<RTCBuildPrimitive> prims;
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (size_t i = 0; i + 2 < positions.size(); i += 3) {
    const glm::vec3 a = positions[i], b = positions[i + 1], c = positions[i + 2];
    const glm::vec3 e1 = b - a, e2 = c - a;
    const float area2 = glm::length(glm::cross(e1, e2));
    if (!(area2 > 0) || !std::isfinite(area2) ||
        !std::isfinite(a.x + a.y + a.z + b.x + b.y + b.z + c.x + c.y + c.z)) {
      out.degenerate++;
      continue;
    }
    BvhTriangle t;
    t.v0 = glm::vec4(a, bits(uint32_t(i / 3)));
    t.e1 = glm::vec4(e1, 0.0f);
    t.e2 = glm::vec4(e2, 0.0f);
    const glm::vec3 l = glm::min(a, glm::min(b, c)), h = glm::max(a, glm::max(b, c));
    RTCBuildPrimitive p{};
    p.lower_x = l.x, p.lower_y = l.y, p.lower_z = l.z, p.geomID = 0;
    p.upper_x = h.x, p.upper_y = h.y, p.upper_z = h.z, p.primID = unsigned(tris.size());
    prims.push_back(p);
    tris.push_back(t);
    lo = glm::min(lo, l), hi = glm::max(hi, h);
  }
  if (tris.empty()) return out;
  if (tris.size() == 1) {  // Embree's builder wants a tree; one triangle is a leaf root
    out.triangles = tris;
    BvhNode root;
    root.lo = glm::vec4(lo, bits(0u | TRI_BVH_LEAF));
    root.hi = glm::vec4(hi, bits(1u));
    out.nodes.push_back(root);
    return out;
  }
  RTCDevice device = rtcNewDevice("threads=0");
  NL_CHECK_MSG(device, "Embree: no device for the BVH builder");
  RTCBVH bvh = rtcNewBVH(device);
  RTCBuildArguments args = rtcDefaultBuildArguments();
  args.byteSize = sizeof(args);
  args.buildFlags = RTC_BUILD_FLAG_NONE;
  args.buildQuality = RTC_BUILD_QUALITY_MEDIUM;  // HIGH's spatial splits need spare primitive slots
  args.maxBranchingFactor = 2;
  args.maxDepth = TRI_BVH_STACK - 4;
  args.sahBlockSize = 1;
  args.minLeafSize = 1;
  args.maxLeafSize = 4;
  args.traversalCost = 1.0f;
  args.intersectionCost = 1.0f;
  args.bvh = bvh;
  args.primitives = prims.data();
  args.primitiveCount = prims.size();
  args.primitiveArrayCapacity = prims.size();
  args.createNode = createNode;
  args.setNodeChildren = setNodeChildren;
  args.setNodeBounds = setNodeBounds;
  args.createLeaf = createLeaf;
  void* root = rtcBuildBVH(&args);
  if (!root) {
    rtcReleaseBVH(bvh);
    rtcReleaseDevice(device);
    NL_CHECK_MSG(false, "Embree: rtcBuildBVH failed");
  }
  out.nodes.reserve(2 * tris.size());
  out.nodes.emplace_back();
  Flattener{tris, out}.write(static_cast<BvhBuildNode*>(root), 0, lo, hi, 0);
  // The nodes live in the BVH's allocator: released with it (their destructors are trivial in
  // effect: nothing they hold owns memory).
  rtcReleaseBVH(bvh);
  rtcReleaseDevice(device);
  return out;
}

namespace {

bool hitBox(const BvhNode& n, const glm::vec3& o, const glm::vec3& inv, float tMin, float tMax) {
  const glm::vec3 t0 = (glm::vec3(n.lo) - o) * inv, t1 = (glm::vec3(n.hi) - o) * inv;
  const glm::vec3 a = glm::min(t0, t1), b = glm::max(t0, t1);
  const float enter = std::max(std::max(a.x, a.y), std::max(a.z, tMin));
  const float exit = std::min(std::min(b.x, b.y), std::min(b.z, tMax));
  return enter <= exit;
}

// Möller and Trumbore, "Fast, Minimum Storage Ray/Triangle Intersection" (1997), as the shader.
float hitTriangle(const BvhTriangle& t, const glm::vec3& o, const glm::vec3& d) {
  const glm::vec3 e1(t.e1), e2(t.e2);
  const glm::vec3 p = glm::cross(d, e2);
  const float det = glm::dot(e1, p);
  if (std::abs(det) < 1e-20f) return -1;
  const float inv = 1.0f / det;
  const glm::vec3 s = o - glm::vec3(t.v0);
  const float u = glm::dot(s, p) * inv;
  if (u < 0 || u > 1) return -1;
  const glm::vec3 q = glm::cross(s, e1);
  const float v = glm::dot(d, q) * inv;
  if (v < 0 || u + v > 1) return -1;
  return glm::dot(e2, q) * inv;
}

}  // namespace

float traceTriangleBvh(const TriangleBvh& bvh, const glm::vec3& o, const glm::vec3& d, float tMin,
                       float tMax) {
  if (bvh.nodes.empty()) return -1;
  const glm::vec3 inv = 1.0f / d;
  uint32_t stack[TRI_BVH_STACK];
  int top = 0;
  stack[top++] = 0;
  float best = -1;
  while (top > 0) {
    const BvhNode& n = bvh.nodes[stack[--top]];
    if (!hitBox(n, o, inv, tMin, tMax)) continue;
    const uint32_t a = ubits(n.lo.w), b = ubits(n.hi.w);
    if (a & TRI_BVH_LEAF) {
      for (uint32_t i = a & ~TRI_BVH_LEAF, e = i + b; i < e; ++i) {
        const float t = hitTriangle(bvh.triangles[i], o, d);
        if (t > tMin && t < tMax) tMax = best = t;
      }
      continue;
    }
    NL_CHECK(top + 2 <= TRI_BVH_STACK);
    stack[top++] = b;
    stack[top++] = a;
  }
  return best;
}

}  // namespace nestlight::gi
