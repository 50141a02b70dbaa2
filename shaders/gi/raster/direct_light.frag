// Direct light from the G-buffer (the `raster` method): every light with its shadow map, the
// BSDF of gi/core's materials, the environment seen behind the scene and its unshadowed light on
// every lobe: irradiance on diffuse lobes (order-2 spherical harmonics, Ramamoorthi and Hanrahan
// 2001, "An Efficient Representation for Irradiance Environment Maps"), the prefiltered sky on
// glossy ones (the split sum, environment_specular.glsl). Scan points emit their colour in
// the radiance-cache mode and are Lambert reflectors of it in the albedo mode, as in gi/reference.
#include "../../interface/frame_interface.glsl"
#include "../common/gbuffer_in.glsl"
#include "../common/lights.glsl"
layout(binding = 0) uniform sampler2D uDepth;
layout(binding = 1) uniform sampler2D uBaseColour;
layout(binding = 2) uniform sampler2D uNormal;
layout(binding = 3) uniform usampler2D uMaterial;
#include "../common/environment.glsl"
#include "../common/environment_specular.glsl"
uniform bool uSkyInDirectLight;  // SceneFrame::setSkyInDirectLight
layout(location = 0) out vec4 outRadiance;

void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  float depth = texelFetch(uDepth, px, 0).r;
  vec2 pixel = gl_FragCoord.xy;
  // Splats sized to the measured spacing leave pin holes where scattered points happen to be far
  // apart (0.6% of a surface at 2.25 spacings, docs/VIEWER.md), through which the background
  // would show. A pixel without geometry whose 3 x 3 neighbourhood is mostly covered takes the
  // nearest covered neighbour's sample (the pass declares a margin of 1 for it); silhouettes,
  // where at most half the neighbours are covered, keep their background.
  if (depth >= 1.0) {
    ivec2 size = ivec2(frame.tile.zw);
    int covered = 0;
    float best = 1.0;
    ivec2 bestPx = px;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        ivec2 q = clamp(px + ivec2(dx, dy), ivec2(0), size - 1);
        float d = texelFetch(uDepth, q, 0).r;
        if (d < 1.0) {
          ++covered;
          if (d < best) best = d, bestPx = q;
        }
      }
    if (covered >= 6) {
      px = bestPx;
      depth = best;
      pixel = vec2(bestPx) + 0.5;
    }
  }
  // The pixel's position in the full image's clip space, then the world.
  vec2 ndc = (pixel / frame.tile.zw) * 2.0 - 1.0;
  // The ray through the near plane: with far / near of 10^7 (a mesh 1000 km from the scan) the
  // far plane's w is lost to float rounding and the sky pixels came out NaN.
  vec4 onNear = frame.worldFromClip * vec4(ndc, -1.0, 1.0);
  vec3 viewDir = normalize(onNear.xyz / onNear.w - frame.eye.xyz);
  if (depth >= 1.0) {
    outRadiance = vec4(environment(viewDir), 1.0);
    return;
  }
  vec4 w = frame.worldFromClip * vec4(ndc, depth * 2.0 - 1.0, 1.0);
  vec3 p = w.xyz / w.w;
  vec4 baseAndRadius = texelFetch(uBaseColour, px, 0);
  vec3 base = baseAndRadius.rgb;
  vec4 nn = texelFetch(uNormal, px, 0);
  uvec4 m = texelFetch(uMaterial, px, 0);
  int source = gbufferSource(m);
  vec3 wo = -viewDir;
  if (source == NL_SOURCE_SCAN && frame.counts.y == 0) {  // radiance cache: the colour is the radiance
    outRadiance = vec4(base, 1.0);
    return;
  }
  vec3 L;
  MaterialParams mat = gbufferMaterial(base, m, L);
  // Two-sided shading, as the reference: the normal faces the viewer; a point without a normal
  // is a disc facing the ray.
  vec3 n = nn.w > 0.0 ? normalize(nn.xyz) : wo;
  if (dot(n, wo) < 0.0) n = -n;
  mat3 frameFromLocal = frameFromNormal(n);
  vec3 woL = wo * frameFromLocal;
  for (int i = 0; i < frame.counts.x; ++i) {
    LightSample s = sampleLight(i, p);
    if (all(lessThanEqual(s.radiance, vec3(0.0)))) continue;
    vec3 wiL = s.wi * frameFromLocal;
    if (wiL.z <= 0.0) continue;
    vec3 f = evalBsdf(mat, woL, wiL);
    if (all(lessThanEqual(f, vec3(0.0)))) continue;
    L += f * s.radiance * wiL.z * visibility(i, p, n, baseAndRadius.a, s);
  }
  if (uHasEnvironment && uSkyInDirectLight) {
    // Unless a GI method gathers the sky itself, occluded.
    L += environmentLight(mat, n, wo);
  }
  outRadiance = vec4(L, 1.0);
}
