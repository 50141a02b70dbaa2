// The change the inserted meshes make to the scan's light, dL = L_with - L_without, at 1 /
// delta_scale of the image (Rohmer, Jendersie and Grosch 2017, section 7). Per scan pixel: N
// cosine directions about its normal; the captured radiance L(x) over their mean incoming light is
// its Lambertian reflectance (eq. 5); the directions that miss the objects' box (F) change
// nothing; of those that meet it (H), `cache` drawn at random (H_a) are traced and the rest (H_b)
// counted, each traced ray giving L_obj - L_env where it meets an object before the scene and 0
// otherwise (Fig. 7), and eq. 9 scales their sum by 1 + |H_b| / |H_a| (unbiased: each hit is
// traced with probability |H_a| / |H|). L_obj is one bounce off the hit voxel, taken as diffuse.
// With vct each traced direction is a cone through the objects' volumes instead (eq. 6): its
// coverage of them times their light less the scene's.
// Beyond the paper: the scene file's lights lit the capture but are no surface of it, so the
// impostor does not hold them. Their part of the light a scan point received, E_i V_i without the
// inserted meshes (shadow maps drawn without them), joins the material estimate's denominator, and
// the inserted meshes' shadows of them are (rho / pi) E_i (V_with - V_without).
layout(local_size_x = 8, local_size_y = 8) in;
#include "../common/gbuffer_in.glsl"
#include "../common/brdf_sample.glsl"
#include "../common/environment.glsl"
#include "../common/lights.glsl"
#include "diffrender_interface.glsl"
#include "diffrender_common.glsl"

layout(binding = 0) uniform sampler2D uDepth;
layout(binding = 2) uniform sampler2D uNormal;
layout(binding = 3) uniform usampler2D uMaterial;
layout(binding = 1) uniform sampler2D uBaseColour;
layout(binding = DR_UNIT_DIRECT) uniform sampler2D uDirect;
layout(binding = DR_UNIT_SHADOW_WITHOUT) uniform sampler2DArrayShadow uShadowWithout;
layout(rgba32f, binding = 0) uniform writeonly image2D uDelta;  // dL, a: 1 where computed
layout(rgba32f, binding = 1) uniform writeonly image2D uGuide;  // the normal, the view distance
layout(rgba32f, binding = 2) uniform writeonly image2D uRho;    // the material estimate (an AOV)
uniform int uScale;        // delta_scale
uniform int uSamples;      // N
uniform int uCache;        // |H_a| at most
uniform bool uEstimateMaterial;
uniform float uRhoMax;

#define DR_SAMPLES_MAX 1024

// The solid angle a query filters over for one of N cosine samples at cos theta to the normal.
float sampleCone(int N, float cone, float cosTheta) {
  if (uQuery == DR_QUERY_VCT) return cone;
  return kPi / (float(N) * max(cosTheta, 0.05));
}

void main() {
  ivec2 lp = ivec2(gl_GlobalInvocationID.xy);
  ivec2 lowSize = (ivec2(frame.tile.zw) + uScale - 1) / uScale;
  if (any(greaterThanEqual(lp, lowSize))) return;
  ivec2 px = min(lp * uScale + uScale / 2, ivec2(frame.tile.zw) - 1);
  float depth = texelFetch(uDepth, px, 0).r;
  uvec4 m = texelFetch(uMaterial, px, 0);
  vec2 ndc = ((vec2(px) + 0.5) / frame.tile.zw) * 2.0 - 1.0;
  vec4 wp = frame.worldFromClip * vec4(ndc, depth * 2.0 - 1.0, 1.0);
  vec3 x = wp.xyz / wp.w;
  vec4 nn = texelFetch(uNormal, px, 0);
  vec3 wo = normalize(frame.eye.xyz - x);
  vec3 n = nn.w > 0.0 ? normalize(nn.xyz) : wo;
  if (dot(n, wo) < 0.0) n = -n;
  imageStore(uGuide, lp, vec4(n, depth < 1.0 ? length(x - frame.eye.xyz) : -1.0));
  if (!(depth < 1.0) || gbufferSource(m) != NL_SOURCE_SCAN) {
    imageStore(uDelta, lp, vec4(0.0));
    imageStore(uRho, lp, vec4(0.0));
    return;
  }
  atomicAdd(stats[DR_STAT_SCAN_PIXELS], 1u);
  ivec2 gpx = px + ivec2(frame.tile.xy);
  // The same sequence every frame (the pixel and the seed): a still camera's frames do not
  // flicker in the viewer, which accumulates nothing.
  rngState = pcgHash(uint(gpx.x) * 9781u + uint(gpx.y) * 6271u + pcgHash(uSeed));
  // The rays meet nothing of the scan itself (the impostor is looked up, the objects' volume
  // marched), so they leave from the surface: a lift would move the objects' shadow.
  vec3 o = x + n * 1e-4 * max(length(x - frame.eye.xyz), 1e-3);
  mat3 F = frameFromNormal(n);
  coneBase = x, coneNormal = n;
  exactLift = 1.5 * texelFetch(uBaseColour, px, 0).a;
  int N = min(uSamples, DR_SAMPLES_MAX);
  // A cone per direction: vct's of solid angle 2 pi / N (the issue's aperture); the impostor's
  // lookups filter over a sample's own 1 / (N pdf) = pi / (N cos theta) (Colbert and Krivanek), so
  // that the ones near the normal, which weigh most, fetch finer levels.
  float cone = 2.0 * kPi / float(N);
  vec2 jitter = rnd2();
  vec3 incoming = vec3(0.0);
  uint hits = 0u;
  // The box hits' indices, for drawing H_a among them (at most 1024 directions: 32 words).
  uint hitBits[32];
  for (int w = 0; w < 32; ++w) hitBits[w] = 0u;
  for (int i = 0; i < N; ++i) {
    // Stratified by a rank-1 lattice (the golden ratio) with one random shift per pixel.
    vec2 u = fract(vec2((float(i) + 0.5) / float(N), float(i) * 0.618034) + jitter);
    vec3 d = F * sampleCosineHemisphereGl(u);
    float omega = sampleCone(N, cone, dot(d, n));
    if (meetsObjectBoxes(o, d)) {
      hitBits[i >> 5] |= 1u << (i & 31);
      hits++;
    }
    if (uEstimateMaterial || uCompareExact) {
      float t;
      vec3 Lq = queryMaterial(o, d, omega, t);
      if (uEstimateMaterial) incoming += Lq;
      if (uCompareExact) compareWithExact(o, d, omega);
    }
  }
  // The scene's lights at the point: what they gave it without the inserted meshes, and the
  // change the meshes' shadows make.
  float radius = texelFetch(uBaseColour, px, 0).a;
  vec3 lightsWithout = vec3(0.0), lightsChange = vec3(0.0);
  for (int i = 0; i < frame.counts.x; ++i) {
    LightSample s = sampleLight(i, x);
    float c = dot(n, s.wi);
    if (!(c > 0.0) || all(lessThanEqual(s.radiance, vec3(0.0)))) continue;
    float with = visibility(i, x, n, radius, s), without = visibilityIn(uShadowWithout, i, x, n, radius, s);
    lightsWithout += s.radiance * c * without;
    lightsChange += s.radiance * c * (with - without);
  }
  vec3 L = texelFetch(uDirect, px, 0).rgb;
  vec3 rho = L;
  if (uEstimateMaterial) {
    vec3 mean = incoming / float(N) + lightsWithout * kInvPi;
    bvec3 dark = lessThanEqual(mean, vec3(1e-12));
    rho = mix(L / max(mean, vec3(1e-12)), vec3(uRhoMax), dark);
  }
  if (any(greaterThan(rho, vec3(uRhoMax))) || any(isnan(rho))) atomicAdd(stats[DR_STAT_RHO_CLAMPED], 1u);
  rho = clamp(rho, vec3(0.0), vec3(uRhoMax));
  imageStore(uRho, lp, vec4(rho, 1.0));
  vec3 delta = vec3(0.0);
  uint traced = min(uint(uCache), hits);
  if (hits > 0u) {
    // Selection sampling (Knuth's algorithm S): each hit is traced with probability traced / hits.
    uint left = hits, need = traced;
    vec3 sum = vec3(0.0);
    uint objectFirst = 0u;
    for (int i = 0; i < N && need > 0u; ++i) {
      if ((hitBits[i >> 5] & (1u << (i & 31))) == 0u) continue;
      bool take = rnd() * float(left) < float(need);
      left--;
      if (!take) continue;
      need--;
      vec2 u = fract(vec2((float(i) + 0.5) / float(N), float(i) * 0.618034) + jitter);
      vec3 d = F * sampleCosineHemisphereGl(u);
      float tScene;
      vec3 Lenv = queryScene(o, d, sampleCone(N, cone, dot(d, n)), tScene);
      if (uQuery == DR_QUERY_VCT) {
        // Eq. 6: the cone's coverage of the objects times their light less the scene's.
        float coverage;
        vec3 Lobj;
        if (!coneObjects(o, d, cone, tScene, coverage, Lobj)) continue;
        objectFirst++;
        sum += coverage * (Lobj - Lenv);
        continue;
      }
      float tHit;
      vec3 hn;
      int material;
      if (!marchObjects(o, d, 0.0, tScene, tHit, hn, material)) continue;
      objectFirst++;
      sum += objectRadiance(o + d * tHit, hn, material) - Lenv;
    }
    delta = (1.0 + float(hits - traced) / float(traced)) * rho / float(N) * sum;
    atomicAdd(stats[DR_STAT_OBJECT_FIRST], objectFirst);
  }
  delta += rho * kInvPi * lightsChange;
  atomicAdd(stats[DR_STAT_BOX_HITS], hits);
  atomicAdd(stats[DR_STAT_TRACED], traced);
  if (unconverged > 0u) atomicAdd(stats[DR_STAT_UNCONVERGED], unconverged);
  if (hidden > 0u) atomicAdd(stats[DR_STAT_HIDDEN], hidden);
  if (compared > 0u) {
    atomicAdd(stats[DR_STAT_COMPARED], compared);
    atomicAdd(stats[DR_STAT_WITHIN_FOOTPRINT], withinFootprint);
    atomicAdd(stats[DR_STAT_COMPARED_SEEN], comparedSeen);
    atomicAdd(stats[DR_STAT_WITHIN_SEEN], withinSeen);
  }
  if (any(isnan(delta)) || any(isinf(delta))) delta = vec3(0.0);
  imageStore(uDelta, lp, vec4(delta, 1.0));
}
