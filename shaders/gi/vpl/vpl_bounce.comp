// The next generation of VPLs (Preiner, section 4.5): each VPL of the last generation sends its
// light one step further. A direction drawn from the cosine distribution (Halton, bases 5 and 7)
// is followed to the nearest of the VPL's ISM points (the same level-of-detail selection, each
// point a disc of its splat's radius facing the VPL); the point becomes a VPL whose incident flux
// is the parent's times its BSDF times pi (emitted flux f cos over the direction's probability
// cos / pi). Nothing hit: the light leaves the scene (its flux is dropped, as the reference's
// escaping paths).
layout(local_size_x = 64) in;
#include "ism_common.glsl"
#include "vpl_material.glsl"
#include "../../common/octahedral.glsl"
layout(std430, binding = VPL_SSBO_RECORDS) buffer Vpls { VplRecord vpls[]; };
uniform int uParentFirst, uChildFirst;  // record ranges of the two generations
uniform int uCount;                     // VPLs per generation
uniform bool uRadianceCache;            // scan points' colour is radiance: light reaching them ends there

float radicalInverse(uint i, uint base) {
  float inv = 1.0 / float(base), f = inv, r = 0.0;
  while (i > 0u) {
    r += float(i % base) * f;
    i /= base;
    f *= inv;
  }
  return r;
}

shared float sBestT[64];
shared int sBest[64];

void main() {
  int k = int(gl_WorkGroupID.x);
  VplRecord parent = vpls[uParentFirst + k];
  VplRecord child;
  child.position = vec4(0.0);
  child.normal = vec4(0.0, 0.0, 1.0, 1.0);
  child.flux = vec4(0.0);
  child.incident = vec4(0.0, 0.0, 1.0, float(NL_NO_MATERIAL));
  child.baseColour = vec4(0.0);
  if (all(equal(parent.flux.rgb, vec3(0.0)))) {
    if (gl_LocalInvocationIndex == 0u) vpls[uChildFirst + k] = child;
    return;
  }
  vec3 x = parent.position.xyz;
  mat3 worldFromLocal = frameFromNormal(parent.normal.xyz);
  uint index = uint(uChildFirst + k + 1);
  vec2 u = vec2(radicalInverse(index, 5u), radicalInverse(index, 7u));
  float r = sqrt(u.x), phi = 2.0 * kPi * u.y;
  vec3 dirLocal = vec3(r * cos(phi), r * sin(phi), sqrt(max(1.0 - u.x, 0.0)));
  vec3 dir = worldFromLocal * dirLocal;

  uint total = includedPoints(x);
  uint stride = max(1u, (total + uPointBudget - 1u) / uPointBudget);
  float grow = sqrt(float(stride));
  float bestT = 3.402823e38;
  int best = -1;
  for (int n = 0; n < uNodeCount; ++n) {
    if (!nodeIncluded(n, x)) continue;
    int first = poolNodes[n].range.x, count = poolNodes[n].range.y;
    uint start = hashU(uint(uParentFirst + k) * 7919u + uint(n)) % stride;
    for (uint i = start + gl_LocalInvocationIndex * stride; i < uint(count); i += gl_WorkGroupSize.x * stride) {
      PoolPoint q = pool[first + int(i)];
      if (q.position.w == VPL_POOL_CLIPPED) continue;
      vec3 d = q.position.xyz - x;
      float dist = length(d);
      // A point stands for the spacing where it lies: its level of detail's (half the wanted
      // spacing, between the deepest taken level's and the wanted one) or, nearer than the scan's
      // finest level reaches, its own measured spacing (stored as its area). The stride thinned
      // the points: each then stands for sqrt(stride) of that. Discs 1.5 of the latter in radius
      // close the thinned surface (every stride-th point in Morton order leaves clumps and gaps:
      // inside a closed sphere, 0.75 let 7% of third-bounce rays out, 1.5 lets 0.4%). Measured in
      // the closed cornell room (1024 VPLs, 4 bounces): without sqrt(stride) on the level of
      // detail's term 31% of bounce rays left between the points and the third and fourth
      // bounces were 23% and 48% dark; with it 0.1% leave and they are within the reference's
      // noise. Wider discs (the wanted spacing itself) catch rays on their overhang past the
      // surfaces' edges: the indirect light rose 5% (11% at 1.5 x) above the reference.
      float radius = grow * max(0.5 * pointSpacing(n, dist), 1.5 * sqrt(uintBitsToFloat(q.surface.w)));
      // Points of the VPL's own surface (within half their disc's radius of its tangent plane)
      // are not hits: the parent's neighbours would catch grazing rays right at their start.
      if (dot(d, parent.normal.xyz) <= 0.5 * radius) continue;
      // A disc in the point's tangent plane (two-sided, as the reference's), or facing the ray
      // when the scan has no normals.
      vec3 nq = decodeNormal(q.surface.x);
      float t = dot(d, dir);
      if (dot(nq, nq) > 0.0) {
        float denom = dot(dir, nq);
        if (abs(denom) < 1e-4) continue;
        t = dot(d, nq) / denom;
      }
      if (!(t > 1e-6) || t >= bestT) continue;
      vec3 off = t * dir - d;
      if (dot(off, off) <= radius * radius) bestT = t, best = first + int(i);
    }
  }
  uint lid = gl_LocalInvocationIndex;
  sBestT[lid] = bestT;
  sBest[lid] = best;
  barrier();
  for (uint s = gl_WorkGroupSize.x / 2u; s > 0u; s >>= 1u) {
    if (lid < s && sBestT[lid + s] < sBestT[lid]) sBestT[lid] = sBestT[lid + s], sBest[lid] = sBest[lid + s];
    barrier();
  }
  if (lid != 0u) return;
  best = sBest[0];
  if (best >= 0 && uRadianceCache && (pool[best].surface.z >> 16) == uint(NL_NO_MATERIAL)) best = -1;
  if (best >= 0) {
    PoolPoint q = pool[best];
    vec3 n = decodeNormal(q.surface.x);
    if (!(dot(n, n) > 0.0)) n = -dir;
    if (dot(n, dir) > 0.0) n = -n;  // two-sided: faces the parent
    vec2 rg = unpackHalf2x16(q.surface.y);
    uint mat = q.surface.z >> 16;
    vec3 base = vec3(rg, unpackHalf2x16(q.surface.z & 0xffffu).x);
    // The parent's BSDF from where its light came to `dir`.
    MaterialParams pm = vplMaterial(parent);
    vec3 wiL = parent.incident.xyz * worldFromLocal;
    vec3 f = wiL.z > 0.0 ? evalBsdf(pm, dirLocal, wiL) : vec3(0.0);
    // A mesh surfel carries its material; a scan point is a Lambert reflector of its colour.
    int type = NL_MATERIAL_LAMBERT;
    float rough = 1.0, metal = 0.0;
    if (mat != uint(NL_NO_MATERIAL)) {
      MaterialRecord rec = materials[mat];
      type = int(rec.baseColor.w), rough = rec.params.x, metal = rec.params.y;
    } else {
      base = min(base, vec3(1.0));
    }
    child.position = vec4(q.position.xyz, q.position.w);
    child.normal = vec4(n, rough);
    child.flux = vec4(parent.flux.rgb * f * kPi, metal);
    child.incident = vec4(-dir, float(mat));
    child.baseColour = vec4(base, float(type));
  }
  vpls[uChildFirst + k] = child;
}
