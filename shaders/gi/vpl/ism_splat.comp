// Splats every VPL's points into its ISM (one workgroup per VPL): distance to the VPL as float
// bits, atomicMin per texel, square splats sized by the point's spacing at its distance
// (shaders/gi/vpl/ism_common.glsl).
layout(local_size_x = 64) in;
#include "ism_common.glsl"
#include "../../common/octahedral.glsl"
layout(std430, binding = VPL_SSBO_RECORDS) readonly buffer Vpls { VplRecord vpls[]; };
layout(std430, binding = VPL_SSBO_ISM) buffer Ism { uint ism[]; };
uniform int uFirstVpl;
void main() {
  int v = uFirstVpl + int(gl_WorkGroupID.x);
  VplRecord r = vpls[v];
  if (all(equal(r.flux.rgb, vec3(0.0)))) return;  // the whole workgroup: a dead VPL has no ISM
  vec3 x = r.position.xyz;
  mat3 worldFromLocal = frameFromNormal(r.normal.xyz);
  uint total = includedPoints(x);
  uint stride = max(1u, (total + uPointBudget - 1u) / uPointBudget);
  int S = uIsmSize;
  uint base = uint(v) * uint(S * S);
  for (int k = 0; k < uNodeCount; ++k) {
    if (!nodeIncluded(k, x)) continue;
    int first = poolNodes[k].range.x, count = poolNodes[k].range.y;
    uint start = hashU(uint(v) * 7919u + uint(k)) % stride;
    for (uint i = start + gl_LocalInvocationIndex * stride; i < uint(count); i += gl_WorkGroupSize.x * stride) {
      PoolPoint q = pool[first + int(i)];
      if (q.position.w == VPL_POOL_CLIPPED) continue;
      vec3 d = q.position.xyz - x;
      float dist = length(d);
      if (!(dist > 1e-6)) continue;
      vec3 local = (d / dist) * worldFromLocal;
      if (local.z <= -0.2) continue;  // behind the VPL's surface, outside its map
      vec2 uv = paraboloid(local);
      if (any(greaterThan(abs(uv), vec2(1.0)))) continue;
      float radius = 0.5 * pointSpacing(k, dist);
      // The VPL's own surface lies at the map's rim and occludes nothing above it.
      if (dot(d, r.normal.xyz) <= 0.5 * radius) continue;
      // A splat seen edge-on covers little: its footprint shrinks with the cosine between its
      // normal and the line of sight (else floor points beside a VPL would shadow the foot of
      // every wall).
      vec3 nq = decodeNormal(q.surface.x);
      if (dot(nq, nq) > 0.0) radius *= max(abs(dot(nq, d / dist)), 0.05);
      int h = clamp(int(ceil(radius / dist * paraboloidScale(local) * 0.5 * float(S) - 0.5)), 0, 3);
      ivec2 c = ivec2((uv * 0.5 + 0.5) * float(S));
      uint bits = floatBitsToUint(dist);
      for (int dy = -h; dy <= h; ++dy)
        for (int dx = -h; dx <= h; ++dx) {
          ivec2 t = c + ivec2(dx, dy);
          if (any(lessThan(t, ivec2(0))) || any(greaterThanEqual(t, ivec2(S)))) continue;
          atomicMin(ism[base + uint(t.y * S + t.x)], bits);
        }
    }
  }
}
