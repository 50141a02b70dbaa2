// The composite (Rohmer, Jendersie and Grosch 2017, sections 6 and 7): scan pixels show the
// capture plus dL, upsampled from 1 / delta_scale by a joint bilateral weight (the neighbours'
// view distance and normal); pixels of the inserted meshes their light gathered from the distance
// impostor by BRDF importance sampling, each sample read at the mip level of its solid angle
// (eq. 3; Colbert and Krivanek 2007), rays their own volume blocks given `ambient` (or, with the
// secondary bounce of the high preset, the light the hit voxel sends back); the scene's
// lights come from the raster frame's direct light on every pixel. With a photograph (section 7,
// Fig. 8) the photo, brought into the scan's colour space by colour-match's C, stands for the
// capture on every pixel but the inserted meshes', and the composite goes back through C^-1.
layout(local_size_x = 8, local_size_y = 8) in;
#include "../common/gbuffer_in.glsl"
#include "../common/brdf_sample.glsl"
#include "../common/environment.glsl"
#include "../common/lights.glsl"
#include "diffrender_interface.glsl"
#include "diffrender_common.glsl"

layout(binding = 0) uniform sampler2D uDepth;
layout(binding = 1) uniform sampler2D uBaseColour;
layout(binding = 2) uniform sampler2D uNormal;
layout(binding = 3) uniform usampler2D uMaterial;
layout(binding = DR_UNIT_DIRECT) uniform sampler2D uDirect;
layout(binding = DR_UNIT_DELTA) uniform sampler2D uDeltaLow;
layout(binding = DR_UNIT_GUIDE) uniform sampler2D uGuideLow;
layout(binding = DR_UNIT_BACKGROUND) uniform sampler2D uBackground;  // the full image's pixels
uniform bool uHasBackground;
uniform mat3 uPhotoToScan, uScanToPhoto;
layout(rgba32f, binding = 0) uniform writeonly image2D uOut;
layout(r32f, binding = 1) uniform writeonly image2D uMask;  // 1 scan, 2 inserted mesh, 0 else (an AOV)
uniform int uScale;
uniform int uObjectSamples;
uniform bool uSelfShadow;
uniform bool uSecondaryBounce;  // a blocked ray sees the light its own voxel sends back
uniform float uAmbient;
uniform float uDeltaGain;  // 1; 0 renders the capture without dL (tests, the "without" image)

// dL at a full-resolution pixel from the four nearest low-resolution samples.
vec3 upsampledDelta(ivec2 px, vec3 n, float dist) {
  ivec2 lowSize = textureSize(uDeltaLow, 0);
  vec2 f = (vec2(px) + 0.5) / float(uScale) - 0.5;
  ivec2 b = ivec2(floor(f));
  vec2 w = f - vec2(b);
  vec3 sum = vec3(0.0);
  float total = 0.0, bestErr = 1e30;
  vec3 best = vec3(0.0);
  for (int k = 0; k < 4; ++k) {
    ivec2 o = ivec2(k & 1, k >> 1);
    ivec2 q = clamp(b + o, ivec2(0), lowSize - 1);
    vec4 g = texelFetch(uGuideLow, q, 0);
    vec4 d = texelFetch(uDeltaLow, q, 0);
    if (d.a <= 0.0 || g.a <= 0.0) continue;
    float bil = (o.x == 1 ? w.x : 1.0 - w.x) * (o.y == 1 ? w.y : 1.0 - w.y);
    float rel = abs(g.a - dist) / max(dist, 1e-6);
    float err = rel + (1.0 - dot(g.xyz, n));
    float weight = max(bil, 1e-3) * exp(-rel / 0.02) * pow(max(dot(g.xyz, n), 0.0), 8.0);
    sum += weight * d.rgb, total += weight;
    if (err < bestErr) bestErr = err, best = d.rgb;
  }
  return total > 1e-6 ? sum / total : best;
}

vec3 shadeObject(vec3 x, vec3 n, vec3 wo, vec3 base, uvec4 m) {
  vec3 emission;
  MaterialParams mat = gbufferMaterial(base, m, emission);
  mat3 F = frameFromNormal(n);
  coneBase = x, coneNormal = n;
  vec3 woL = vec3(dot(wo, F[0]), dot(wo, F[1]), dot(wo, F[2]));
  // Past the boundary voxels of the shaded surface itself.
  float leave = 1.5 * length(volumeCell(max(volumeAt(x), 0)));
  vec3 xo = x + n * max(1e-4 * max(length(x - frame.eye.xyz), 1e-3), 1e-4);
  vec3 sum = vec3(0.0);
  uint blocked = 0u;
  for (int i = 0; i < uObjectSamples; ++i) {
    vec3 wiL;
    vec2 u = rnd2();
    if (!sampleBsdf(mat, woL, u, rnd(), wiL)) continue;
    float pdf = pdfBsdf(mat, woL, wiL);
    if (!(pdf > 0.0)) continue;
    vec3 w = F * wiL;
    vec3 Li;
    float tHit;
    vec3 hn;
    int hm;
    if (uSelfShadow && marchObjects(xo, w, leave, kImpostorFar, tHit, hn, hm)) {
      Li = uSecondaryBounce ? objectRadiance(xo + w * tHit, hn, hm) : vec3(uAmbient);
      blocked++;
    } else {
      float t;
      Li = queryScene(xo, w, 1.0 / (float(uObjectSamples) * pdf), t);
    }
    sum += evalBsdf(mat, woL, wiL) * wiL.z * Li / pdf;
  }
  if (blocked > 0u) atomicAdd(stats[DR_STAT_SELF_SHADOWED], blocked);
  return sum / float(max(uObjectSamples, 1));
}

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(px, ivec2(frame.tile.zw)))) return;
  vec4 direct = texelFetch(uDirect, px, 0);
  float depth = texelFetch(uDepth, px, 0).r;
  // The photograph in the scan's colours, where it stands for the capture.
  vec3 photo = uHasBackground ? uPhotoToScan * texelFetch(uBackground, px + ivec2(frame.tile.xy), 0).rgb : vec3(0.0);
  if (!(depth < 1.0)) {
    imageStore(uOut, px, uHasBackground ? vec4(uScanToPhoto * photo, direct.a) : direct);
    imageStore(uMask, px, vec4(0.0));
    return;
  }
  uvec4 m = texelFetch(uMaterial, px, 0);
  vec2 ndc = ((vec2(px) + 0.5) / frame.tile.zw) * 2.0 - 1.0;
  vec4 wp = frame.worldFromClip * vec4(ndc, depth * 2.0 - 1.0, 1.0);
  vec3 x = wp.xyz / wp.w;
  vec3 wo = normalize(frame.eye.xyz - x);
  vec4 nn = texelFetch(uNormal, px, 0);
  vec3 n = nn.w > 0.0 ? normalize(nn.xyz) : wo;
  if (dot(n, wo) < 0.0) n = -n;
  int source = gbufferSource(m);
  bool object = source == NL_SOURCE_MESH && inObjects(x);
  vec3 L = uHasBackground && !object ? photo : direct.rgb;
  float mask = 0.0;
  if (source == NL_SOURCE_SCAN) {
    mask = 1.0;
    // The objects can take away at most all the light there was: eq. 9's estimate is unbiased
    // but not bounded by the capture, and a neighbour's dL can be larger than a dark pixel's.
    L = max(L + uDeltaGain * upsampledDelta(px, n, length(x - frame.eye.xyz)), vec3(0.0));
  } else if (object) {
    atomicAdd(stats[DR_STAT_OBJECT_PIXELS], 1u);
    mask = 2.0;
    ivec2 gpx = px + ivec2(frame.tile.xy);
    // The same sequence every frame: no flicker under a still camera.
    rngState = pcgHash(uint(gpx.x) * 7919u + uint(gpx.y) * 104729u + pcgHash(uSeed * 3u + 1u));
    L += shadeObject(x, n, wo, texelFetch(uBaseColour, px, 0).rgb, m);
  }
  if (unconverged > 0u) atomicAdd(stats[DR_STAT_UNCONVERGED], unconverged);
  if (hidden > 0u) atomicAdd(stats[DR_STAT_HIDDEN], hidden);
  if (any(isnan(L)) || any(isinf(L))) L = direct.rgb;
  if (uHasBackground) L = uScanToPhoto * L;
  imageStore(uOut, px, vec4(L, direct.a));
  imageStore(uMask, px, vec4(mask));
}
