// The geometry-aware filter of interleaved sampling (Keller and Heidrich 2001; Preiner, section
// 4.4): each pixel averages the demodulated indirect light of the n x n window around it (every
// VPL subset once), counting a neighbour only when it lies on the same surface (normals within
// 25 degrees, within 2% of the pixel's distance of its tangent plane), then modulates by its own albedo and adds
// the direct light. The clamp's loss goes to alpha, for the frame's bias measure.
#include "../common/gbuffer_in.glsl"
layout(binding = 0) uniform sampler2D uDepth;
layout(binding = 1) uniform sampler2D uBaseColour;
layout(binding = 2) uniform sampler2D uNormal;
layout(binding = 3) uniform usampler2D uMaterial;
layout(binding = 4) uniform sampler2D uIndirect;
layout(binding = 5) uniform sampler2D uClampLoss;
layout(binding = 6) uniform sampler2D uDirect;
uniform int uInterleave;
layout(location = 0) out vec4 outRadiance;

vec3 worldAt(ivec2 px, float depth) {
  vec2 ndc = ((vec2(px) + 0.5) / frame.tile.zw) * 2.0 - 1.0;
  vec4 w = frame.worldFromClip * vec4(ndc, depth * 2.0 - 1.0, 1.0);
  return w.xyz / w.w;
}

void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  vec3 direct = texelFetch(uDirect, px, 0).rgb;
  float depth = texelFetch(uDepth, px, 0).r;
  uvec4 m = texelFetch(uMaterial, px, 0);
  if (!(depth < 1.0) || (gbufferSource(m) == NL_SOURCE_SCAN && frame.counts.y == 0)) {
    outRadiance = vec4(direct, 0.0);
    return;
  }
  vec3 p = worldAt(px, depth);
  float range = length(p - frame.eye.xyz);
  vec3 n = texelFetch(uNormal, px, 0).xyz;
  bool hasNormal = texelFetch(uNormal, px, 0).w > 0.0;
  int N = uInterleave, lo = -(N / 2);
  ivec2 size = ivec2(frame.tile.zw);
  vec3 sum = vec3(0.0), lossSum = vec3(0.0);
  float wsum = 0.0;
  for (int dy = lo; dy < lo + N; ++dy)
    for (int dx = lo; dx < lo + N; ++dx) {
      ivec2 q = px + ivec2(dx, dy);
      if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
      float dq = texelFetch(uDepth, q, 0).r;
      if (!(dq < 1.0)) continue;
      vec4 nq = texelFetch(uNormal, q, 0);
      if (hasNormal && nq.w > 0.0 && abs(dot(nq.xyz, n)) < 0.9) continue;
      // Off the pixel's tangent plane (or, without a normal, away in depth): another surface.
      vec3 offset = worldAt(q, dq) - p;
      float apart = hasNormal ? abs(dot(offset, n)) : abs(length(offset + p - frame.eye.xyz) - range);
      if (apart > 0.02 * range) continue;
      sum += texelFetch(uIndirect, q, 0).rgb;
      lossSum += texelFetch(uClampLoss, q, 0).rgb;
      wsum += 1.0;
    }
  vec3 emission;
  MaterialParams mat = gbufferMaterial(texelFetch(uBaseColour, px, 0).rgb, m, emission);
  vec3 a = albedoEstimate(mat);
  vec3 indirect = wsum > 0.0 ? sum / wsum * max(a, vec3(1e-3)) : vec3(0.0);
  vec3 loss = wsum > 0.0 ? lossSum / wsum : vec3(0.0);
  outRadiance = vec4(direct + indirect, luminance(loss));
}
