// Visibility V(x, w) of the environment: rays against the inserted meshes' triangles through their
// BVH (gi/ibl/triangle_bvh.h; gi::ibl::traceTriangleBvh is this traversal on the CPU).
layout(std430, binding = IBL_SSBO_BVH) readonly buffer IblBvh { IblBvhNode bvh[]; };
layout(std430, binding = IBL_SSBO_TRIANGLES) readonly buffer IblTriangles { IblTriangle triangles[]; };
uniform int uBvhNodes;  // 0: no meshes

bool iblHitBox(IblBvhNode n, vec3 o, vec3 inv, float tMax) {
  vec3 t0 = (n.lo.xyz - o) * inv, t1 = (n.hi.xyz - o) * inv;
  vec3 a = min(t0, t1), b = max(t0, t1);
  float enter = max(max(a.x, a.y), max(a.z, 0.0));
  float exit = min(min(b.x, b.y), min(b.z, tMax));
  return enter <= exit;
}

// Möller and Trumbore (1997).
float iblHitTriangle(IblTriangle t, vec3 o, vec3 d) {
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
  uint stack[IBL_BVH_STACK];
  int top = 0;
  stack[top++] = 0u;
  while (top > 0) {
    IblBvhNode n = bvh[stack[--top]];
    if (!iblHitBox(n, o, inv, tMax)) continue;
    uint a = floatBitsToUint(n.lo.w), b = floatBitsToUint(n.hi.w);
    if ((a & IBL_BVH_LEAF) != 0u) {
      for (uint i = a & ~IBL_BVH_LEAF, e = i + b; i < e; ++i) {
        float t = iblHitTriangle(triangles[i], o, d);
        if (t > 0.0 && t < tMax) return true;
      }
      continue;
    }
    if (top + 2 > IBL_BVH_STACK) return false;  // deeper than the builder makes (a CHECK on the CPU)
    stack[top++] = b;
    stack[top++] = a;
  }
  return false;
}
