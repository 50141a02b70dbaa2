// Indirect light from the VPLs at every camera G-buffer pixel (Preiner, section 4.4), with
// interleaved sampling (Keller and Heidrich 2001, "Interleaved Sampling"): the pixel at (x, y)
// takes only the VPLs of subset (x mod n) + n (y mod n), each weighted n^2, and the
// geometry-aware filter (vpl_filter.frag) gathers the n x n subsets back. Each VPL emits its
// incident flux times its BSDF and cosine; ISMs give its visibility.
//
// The VPL singularity: 1 / d^2 is clamped to 1 / d_c^2 (d_c = the clamp distance), the usual
// remedy (Keller 1997, "Instant Radiosity" and its successors). The light the clamp removes is
// written beside the result (location 1), so its bias is measured, not guessed.
//
// Output 0 is demodulated (divided by the receiver's albedo) so that the filter averages light,
// not texture; the filter modulates it back.
#include "vpl_material.glsl"
layout(std430, binding = VPL_SSBO_RECORDS) readonly buffer Vpls { VplRecord vpls[]; };
layout(std430, binding = VPL_SSBO_ISM) readonly buffer Ism { uint ism[]; };
#if VPL_EXACT_VISIBILITY  // visibility "exact": the ISMs counted against Embree's rays
layout(std430, binding = VPL_SSBO_EXACT) readonly buffer Exact { uint exactBits[]; };
layout(std430, binding = VPL_SSBO_AGREEMENT) buffer Agreement { uint agreement[]; };
#endif
layout(binding = 0) uniform sampler2D uDepth;
layout(binding = 1) uniform sampler2D uBaseColour;
layout(binding = 2) uniform sampler2D uNormal;
layout(binding = 3) uniform usampler2D uMaterial;
uniform int uVplCount;     // all generations
uniform int uInterleave;   // n
uniform int uIsmSize;
uniform float uClampDistance;
uniform float uIsmBias;    // depth bias, in ISM texel footprints
uniform int uVisibility;   // 0: none (every VPL sees every receiver), 1: ISMs, 2: exact (Embree bits; ISMs counted against them)
uniform int uExactWords;   // words per pixel of the exact bits (tile pixels, row-major from the tile's corner)
layout(location = 0) out vec4 outIndirect;
layout(location = 1) out vec4 outClampLoss;

// The receiver's albedo the filter demodulates by (never 0: black receivers stay black).
vec3 demodulation(MaterialParams mat) {
  vec3 a = albedoEstimate(mat);
  return max(a, vec3(1e-3));
}

// Slope-scaled bias: an ISM texel holds the nearest of the directions it spans, and across a
// texel a surface seen at incidence alpha recedes by dist x texel angle x tan(alpha); the test
// allows uIsmBias such texels (and the VPL's own splat radius).
float ismVisibility(int k, VplRecord v, vec3 p, float dist, vec3 local, float cosReceiver) {
  vec2 uv = local.xy / (1.0 + local.z);
  float S = float(uIsmSize);
  vec2 f = (uv * 0.5 + 0.5) * S - 0.5;
  ivec2 t0 = ivec2(floor(f));
  vec2 w = f - vec2(t0);
  float tanAlpha = min(sqrt(max(1.0 - cosReceiver * cosReceiver, 0.0)) / max(cosReceiver, 1e-3), 4.0);
  float bias = uIsmBias * dist * (4.0 / S) / max(1.0 + local.z, 1e-3) * (1.0 + tanAlpha) + v.position.w;
  // Bilinear percentage-closer: the four nearest texels' tests, weighted.
  float vis = 0.0;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      ivec2 t = clamp(t0 + ivec2(i, j), ivec2(0), ivec2(uIsmSize - 1));
      float d = uintBitsToFloat(ism[uint(k) * uint(uIsmSize * uIsmSize) + uint(t.y * uIsmSize + t.x)]);
      float test = dist <= d + bias ? 1.0 : 0.0;
      vis += test * (i == 0 ? 1.0 - w.x : w.x) * (j == 0 ? 1.0 - w.y : w.y);
    }
  return vis;
}

void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  outIndirect = vec4(0.0);
  outClampLoss = vec4(0.0);
  float depth = texelFetch(uDepth, px, 0).r;
  if (!(depth < 1.0)) return;
  uvec4 m = texelFetch(uMaterial, px, 0);
  if (gbufferSource(m) == NL_SOURCE_SCAN && frame.counts.y == 0) return;  // radiance cache: its colour is all its light
  vec2 ndc = (gl_FragCoord.xy / frame.tile.zw) * 2.0 - 1.0;
  vec4 wp = frame.worldFromClip * vec4(ndc, depth * 2.0 - 1.0, 1.0);
  vec3 p = wp.xyz / wp.w;
  vec3 wo = normalize(frame.eye.xyz - p);
  vec4 nn = texelFetch(uNormal, px, 0);
  vec3 n = nn.w > 0.0 ? normalize(nn.xyz) : wo;
  if (dot(n, wo) < 0.0) n = -n;
  vec3 emission;
  MaterialParams mat = gbufferMaterial(texelFetch(uBaseColour, px, 0).rgb, m, emission);
  mat3 receiverFrame = frameFromNormal(n);
  vec3 woL = wo * receiverFrame;

  int N = uInterleave;
  ivec2 g = ivec2(frame.tile.xy) + px;  // the full image's pixel: tiles take the same subsets
  int subset = (g.x % N) + N * (g.y % N);
  vec3 L = vec3(0.0), loss = vec3(0.0);
  float agreeWeight = 0.0, compareWeight = 0.0;  // visibility "exact": light on which the ISMs agreed
  float clamp2 = uClampDistance * uClampDistance;
  for (int k = subset; k < uVplCount; k += N * N) {
    VplRecord v = vpls[k];
    if (all(equal(v.flux.rgb, vec3(0.0)))) continue;
    vec3 d = p - v.position.xyz;
    float d2 = dot(d, d);
    if (!(d2 > 0.0)) continue;
    float dist = sqrt(d2);
    vec3 w = d / dist;  // from the VPL to the receiver
    float cosR = -dot(n, w);
    if (cosR <= 0.0) continue;
    mat3 vplFrame = frameFromNormal(v.normal.xyz);
    vec3 wL = w * vplFrame;
    if (wL.z <= 0.0) continue;
    vec3 inL = v.incident.xyz * vplFrame;
    if (inL.z <= 0.0) continue;
    vec3 fv = evalBsdf(vplMaterial(v), wL, inL);
    vec3 fr = evalBsdf(mat, woL, (-w) * receiverFrame);
    vec3 c = v.flux.rgb * fv * wL.z * fr * cosR;
    if (all(equal(c, vec3(0.0)))) continue;
    if (uVisibility == 1) {
      c *= ismVisibility(k, v, p, dist, wL, cosR);
    }
#if VPL_EXACT_VISIBILITY
    else if (uVisibility == 2) {
      int slot = k / (N * N);
      uint word = exactBits[(px.y * int(frame.tile.z) + px.x) * uExactWords + slot / 32];
      bool seen = ((word >> uint(slot % 32)) & 1u) != 0u;
      bool ismSeen = ismVisibility(k, v, p, dist, wL, cosR) >= 0.5;
      float weight = luminance(c / max(d2, clamp2));
      if (seen == ismSeen) agreeWeight += weight;
      compareWeight += weight;
      atomicAdd(agreement[1], 1u);
      // Constant indices: a computed one was among what the program NVIDIA's compiler failed on.
      if (seen == ismSeen) atomicAdd(agreement[0], 1u);
      else if (seen) atomicAdd(agreement[2], 1u);
      else atomicAdd(agreement[3], 1u);
      if (!seen) c = vec3(0.0);
    }
#endif
    L += c / max(d2, clamp2);
    loss += c * (1.0 / d2 - 1.0 / max(d2, clamp2));
  }
#if VPL_EXACT_VISIBILITY
  if (uVisibility == 2 && compareWeight > 0.0) {  // per pixel, in 1/1024ths
    atomicAdd(agreement[4], uint(1024.0 * agreeWeight / compareWeight + 0.5));
    atomicAdd(agreement[5], 1024u);
  }
#endif
  float weight = float(N * N);
  outIndirect = vec4(L * weight / demodulation(mat), 1.0);
  outClampLoss = vec4(loss * weight, 1.0);
}
