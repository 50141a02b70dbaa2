// Visibility V(x, w) of the environment: rays against the inserted meshes' triangles through their
// BVH (gi/shared/triangle_bvh.h; gi::traceTriangleBvh is this traversal on the CPU), and
// against the scan's resident cut (below).
#include "../shared/triangle_bvh_interface.glsl"
layout(std430, binding = IBL_SSBO_BVH) readonly buffer IblBvh { TriBvhNode bvh[]; };
layout(std430, binding = IBL_SSBO_TRIANGLES) readonly buffer TriBvhTriangles { TriBvhTriangle triangles[]; };
uniform int uBvhNodes;  // 0: no meshes
// Loop iterations this invocation ran (llvmpipe stops every loop of an invocation after 65,535 in
// all: the frame counts the pixels that came near).
uint loopSteps = 0u;

bool iblHitBox(TriBvhNode n, vec3 o, vec3 inv, float tMax) {
  vec3 t0 = (n.lo.xyz - o) * inv, t1 = (n.hi.xyz - o) * inv;
  vec3 a = min(t0, t1), b = max(t0, t1);
  float enter = max(max(a.x, a.y), max(a.z, 0.0));
  float exit = min(min(b.x, b.y), min(b.z, tMax));
  return enter <= exit;
}

// Möller and Trumbore (1997).
float iblHitTriangle(TriBvhTriangle t, vec3 o, vec3 d) {
  vec3 p = cross(d, t.e2.xyz);
  float det = dot(t.e1.xyz, p);
  if (abs(det) < 1e-20) return -1.0;
  float inv = 1.0 / det;
  vec3 s = o - t.v0.xyz;
  float u = dot(s, p) * inv;
  if (u < 0.0 || u > 1.0) return -1.0;
  vec3 q = cross(s, t.e1.xyz);
  float v = dot(d, q) * inv;
  if (v < 0.0 || u + v > 1.0) return -1.0;
  return dot(t.e2.xyz, q) * inv;
}

// Whether anything of the meshes lies along o + t d, 0 < t < tMax (any hit ends the search).
bool meshesOcclude(vec3 o, vec3 d, float tMax) {
  if (uBvhNodes == 0) return false;
  vec3 inv = 1.0 / d;
  uint stack[TRI_BVH_STACK];
  int top = 0;
  stack[top++] = 0u;
  while (top > 0) {
    TriBvhNode n = bvh[stack[--top]];
    loopSteps++;
    if (!iblHitBox(n, o, inv, tMax)) continue;
    uint a = floatBitsToUint(n.lo.w), b = floatBitsToUint(n.hi.w);
    if ((a & TRI_BVH_LEAF) != 0u) {
      for (uint i = a & ~TRI_BVH_LEAF, e = i + b; i < e; ++i) {
        float t = iblHitTriangle(triangles[i], o, d);
        if (t > 0.0 && t < tMax) return true;
      }
      continue;
    }
    if (top + 2 > TRI_BVH_STACK) return false;  // deeper than the builder makes (a CHECK on the CPU)
    stack[top++] = b;
    stack[top++] = a;
  }
  return false;
}

// And against the resident cut of the scan: its points as discs (the leaves of the per-node
// bounding-sphere hierarchies of the pbgi method, gi/shared/cut_hierarchies.h, joined by their top
// tree): spheres and slabs bound the rays' search, a leaf is a disc of its radius about its
// normal (without a normal, a disc facing the ray).
#include "../shared/bsh_interface.glsl"
#include "../pbgi/pbgi_nodes.glsl"
#include "../../common/octahedral.glsl"
uniform int uTopCount;  // 0: nothing resident

// A node as fetchNode reads it, but with colour as stored: in ibl's hierarchies an inner node's
// colour holds its slab (gi/ibl/src/ibl_method.cpp, SlabBshLayer), not a colour to scale.
BshNode iblFetchNode(uvec2 e) {
  if (e.y == 0u) return top[e.x];
  PbgiNode cn = cutNodes[e.y - 1u];
  BshNode A = nodes[cn.range.x + e.x];
  A.sphere.xyz += cn.origin.xyz;
  return A;
}

bool scanOccludes(vec3 o, vec3 d, float tMax) {
  if (uTopCount == 0) return false;
  uvec2 stack[PBGI_STACK];
  int top = 0;
  stack[top++] = uvec2(0u, 0u);
  while (top > 0) {
    uvec2 e = stack[--top];
    loopSteps++;
    BshNode A = iblFetchNode(e);
    vec3 oc = A.sphere.xyz - o;
    float tc = dot(oc, d), r = A.sphere.w;
    float dist2 = max(dot(oc, oc) - tc * tc, 0.0);
    if (dist2 > r * r || tc + r <= 0.0 || tc - r >= tMax) continue;
    if (A.links.x != BSH_LEAF && e.y != 0u && A.colour.z > 0.0) {
      // The ray's heights along the node's axis over its chord through the sphere are linear in
      // t: where they miss the slab every disc below lies, nothing below is met (a ray leaving its
      // own flat surface, or passing over a distant one).
      vec3 n = decodeNormal(A.links.w);
      float halfChord = sqrt(max(r * r - dist2, 0.0));
      float t0 = max(tc - halfChord, 0.0), t1 = min(tc + halfChord, tMax);
      float h0 = dot(-oc, n), dn = dot(d, n);
      float ha = h0 + t0 * dn, hb = h0 + t1 * dn;
      // The slab was measured in the node's frame; here centres carry the scene frame's rounding.
      float pad = 2.4e-7 * max(max(abs(A.sphere.x), abs(A.sphere.y)), abs(A.sphere.z));
      if (max(ha, hb) < A.colour.x - pad || min(ha, hb) > A.colour.y + pad) continue;
    }
    if (A.links.x == BSH_LEAF) {
      if (e.y == 0u) {  // a top-tree leaf: enter that node's own hierarchy
        stack[top++] = uvec2(0u, A.links.y + 1u);
        continue;
      }
      float disc = min(uintBitsToFloat(A.links.y), r);
      if (A.links.w == 0u) {
        if (dist2 <= disc * disc && tc > 0.0 && tc < tMax) return true;
        continue;
      }
      vec3 n = decodeNormal(A.links.w);
      float dn = dot(d, n);
      if (abs(dn) < 1e-8) continue;
      float t = dot(oc, n) / dn;
      if (!(t > 0.0 && t < tMax)) continue;
      vec3 p = o + t * d - A.sphere.xyz;
      if (dot(p, p) <= disc * disc) return true;
      continue;
    }
    if (top + 2 > PBGI_STACK) return false;  // deeper than two BSH_MAX_DEPTH hierarchies: cannot happen
    stack[top++] = uvec2(A.links.y, e.y);
    stack[top++] = uvec2(A.links.x, e.y);
  }
  return false;
}
