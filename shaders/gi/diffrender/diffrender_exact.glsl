// The exact query: rays against the scan's resident cut as discs (the leaves of the per-node
// bounding-sphere hierarchies of gi/shared/cut_hierarchies.h, unpruned: every leaf a point's disc,
// joined by their top tree), the nearest hit's radiance, so that a benchmark isolates the
// impostor's and the volume's approximations from the rest. The captured scene's meshes
// (`inserted` false: a lamp, a light panel) are traced too, through their triangle BVH
// (gi/shared/triangle_bvh.h), showing what the impostor holds of them: their emission.
#include "../shared/bsh_interface.glsl"
#include "../pbgi/pbgi_nodes.glsl"
#include "../../common/octahedral.glsl"
uniform int uTopCount;  // 0: nothing resident
#include "../shared/triangle_bvh_interface.glsl"
layout(std430, binding = DR_SSBO_MESH_BVH) readonly buffer DrMeshBvh { TriBvhNode meshBvh[]; };
layout(std430, binding = DR_SSBO_MESH_TRIANGLES) readonly buffer DrMeshTriangles {
  TriBvhTriangle meshTriangles[];
};
uniform int uMeshBvhNodes;  // 0: no captured mesh
uniform bool uCompareExact;
vec3 exactNormal = vec3(0.0);  // the last hit disc's normal (one facing the ray when it has none)

// The nearest disc along o + t d, 0 < t < tMax: its radiance and distance; false when none.
bool traceScan(vec3 o, vec3 d, float tMax, out vec3 radiance, out float tHit) {
  radiance = vec3(0.0), tHit = kImpostorFar;
  if (uTopCount == 0) return false;
  bool hit = false;
  uvec2 stack[PBGI_STACK];
  int top = 0;
  stack[top++] = uvec2(0u, 0u);
  for (int guard = 0; top > 0 && guard < 60000; ++guard) {
    uvec2 e = stack[--top];
    BshNode A = fetchNode(e);
    vec3 oc = A.sphere.xyz - o;
    float tc = dot(oc, d), r = A.sphere.w;
    float dist2 = max(dot(oc, oc) - tc * tc, 0.0);
    if (dist2 > r * r || tc + r <= 0.0 || tc - r >= tMax) continue;
    if (A.links.x == BSH_LEAF) {
      if (e.y == 0u) {  // a top-tree leaf: enter that node's own hierarchy
        if (top < PBGI_STACK) stack[top++] = uvec2(0u, A.links.y + 1u);
        continue;
      }
      float disc = min(uintBitsToFloat(A.links.y), r), t = -1.0;
      if (A.links.w == 0u) {
        if (dist2 <= disc * disc) t = tc;  // no normal: a disc facing the ray
      } else {
        vec3 n = decodeNormal(A.links.w);
        float dn = dot(d, n);
        if (abs(dn) < 1e-8) continue;
        t = dot(oc, n) / dn;
        vec3 p = o + t * d - A.sphere.xyz;
        if (dot(p, p) > disc * disc) t = -1.0;
      }
      if (t > 0.0 && t < tMax) {
        tMax = t, tHit = t, radiance = A.colour.rgb, hit = true;
        exactNormal = A.links.w == 0u ? -d : decodeNormal(A.links.w);
      }
      continue;
    }
    if (top + 2 > PBGI_STACK) break;
    // The nearer child last, so that it is visited first and shortens the search.
    BshNode L = fetchNode(uvec2(A.links.x, e.y)), R = fetchNode(uvec2(A.links.y, e.y));
    bool leftFirst = dot(L.sphere.xyz - o, d) < dot(R.sphere.xyz - o, d);
    stack[top++] = uvec2(leftFirst ? A.links.y : A.links.x, e.y);
    stack[top++] = uvec2(leftFirst ? A.links.x : A.links.y, e.y);
  }
  return hit;
}

// The nearest captured mesh's triangle along o + t d, 0 < t < tMax (Moller and Trumbore's test):
// its material, tMax shortened to it and exactNormal set; -1 when none is nearer.
int traceCapturedMeshes(vec3 o, vec3 d, inout float tMax) {
  if (uMeshBvhNodes == 0) return -1;
  vec3 inv = 1.0 / d;
  uint stack[TRI_BVH_STACK];
  int top = 0, material = -1;
  stack[top++] = 0u;
  while (top > 0) {
    TriBvhNode n = meshBvh[stack[--top]];
    vec3 t0 = (n.lo.xyz - o) * inv, t1 = (n.hi.xyz - o) * inv;
    vec3 lo = min(t0, t1), hi = max(t0, t1);
    if (max(max(lo.x, lo.y), max(lo.z, 0.0)) > min(min(hi.x, hi.y), min(hi.z, tMax))) continue;
    uint a = floatBitsToUint(n.lo.w), b = floatBitsToUint(n.hi.w);
    if ((a & TRI_BVH_LEAF) != 0u) {
      for (uint i = a & ~TRI_BVH_LEAF, e = i + b; i < e; ++i) {
        TriBvhTriangle tr = meshTriangles[i];
        vec3 p = cross(d, tr.e2.xyz);
        float det = dot(tr.e1.xyz, p);
        if (abs(det) < 1e-20) continue;
        vec3 s = o - tr.v0.xyz;
        float u = dot(s, p) / det;
        vec3 q = cross(s, tr.e1.xyz);
        float v = dot(d, q) / det, t = dot(tr.e2.xyz, q) / det;
        if (u < 0.0 || u > 1.0 || v < 0.0 || u + v > 1.0 || !(t > 0.0) || t >= tMax) continue;
        tMax = t;
        material = int(floatBitsToUint(tr.v0.w));
        exactNormal = normalize(cross(tr.e1.xyz, tr.e2.xyz));
      }
      continue;
    }
    if (top + 2 > TRI_BVH_STACK) break;
    stack[top++] = b;
    stack[top++] = a;
  }
  return material;
}

// The nearest of the scan's discs and the captured meshes along o + t d: its radiance (a mesh's
// emission) and distance; false when the ray leaves to the environment.
bool traceExact(vec3 o, vec3 d, out vec3 radiance, out float tHit) {
  bool scan = traceScan(o, d, kImpostorFar, radiance, tHit);
  float t = scan ? tHit : kImpostorFar;
  int m = traceCapturedMeshes(o, d, t);
  if (m < 0) return scan;
  radiance = materials[m].emission.rgb, tHit = t;
  return true;
}

vec3 exactQuery(vec3 o, vec3 d, out float tScene) {
  vec3 L;
  if (traceExact(o + coneNormal * exactLift, d, L, tScene)) return L;
  tScene = kImpostorFar;
  return environment(d);
}

// compare_exact: of the rays whose exact trace meets the scene, how many hits of the query lie within
// the footprint of an impostor texel about the exact hit. A texel spans about 2 / size radians
// from the centre; on the surface its footprint stretches by one over the cosine between the
// surface and the line of sight from the centre (capped at 10x: a surface seen edge-on).
uint compared = 0u, withinFootprint = 0u, comparedSeen = 0u, withinSeen = 0u;
void compareWithExact(vec3 o, vec3 d, float solidAngle) {
  vec3 oe = o + coneNormal * exactLift, L;
  float te;
  if (!traceExact(oe, d, L, te)) return;
  compared++;
  float tQuery = te;
  if (uQuery != DR_QUERY_EXACT) {
    uint u = unconverged, h = hidden;
    queryScene(oe, d, solidAngle, tQuery);
    unconverged = u, hidden = h;
  }
  vec3 pe = oe + te * d, r = pe - uImpostorCentre;
  float dist = length(r);
  if (tQuery >= kImpostorFar * 0.5) tQuery = -1.0;  // the query saw the environment
  float cosView = abs(dot(exactNormal, r)) / max(dist, 1e-20);
  float texel = 2.0 * dist / float(uImpostorSize) / max(cosView, 0.1);
  // Along the ray: the exact hit is from the lifted origin, so the query's is taken from there too.
  bool within = abs(tQuery - te) <= texel;
  if (within) withinFootprint++;
  // Whether the impostor holds the exact hit (its stored distance there within two texels'
  // footprint): a hit its centre does not see no query of it can find.
  if (abs(impostorDistance(r) - dist) <= 2.0 * footprint(r)) {
    comparedSeen++;
    if (within) withinSeen++;
  }
}
