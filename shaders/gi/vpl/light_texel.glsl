// A texel of the light G-buffer (the lights' views of the scene, one layer per shadow-map view)
// as the patch of surface it stands for: where it is, which way it faces, its BSDF, and the flux
// it receives from its light: intensity x the texel's solid angle (perspective layers: point and
// spot lights) or irradiance x the texel's area (orthographic: directional lights). Paper:
// Preiner, "Real-Time Global Illumination in Point Clouds" (the light G-buffer, section 4.1).
#include "../../interface/frame_interface.glsl"
#include "vpl_interface.glsl"
#include "../common/gbuffer_in.glsl"
#include "../common/lights.glsl"
layout(std430, binding = VPL_SSBO_LIGHT_VIEWS) readonly buffer LightViews { LightView lightViews[]; };
layout(binding = 0) uniform sampler2DArray uLightDepth;
layout(binding = 1) uniform sampler2DArray uLightBase;
layout(binding = 2) uniform sampler2DArray uLightNormal;
layout(binding = 3) uniform usampler2DArray uLightMaterial;

struct LightTexel {
  bool valid;
  vec3 p, n, wi;     // position, normal facing the light, direction towards the light
  vec3 fluxIn;       // W arriving on the patch
  MaterialParams mat;
  uint materialIndex;
  float radius;      // splat radius of a scan point (0: meshes)
};

LightTexel lightTexel(ivec3 t) {
  LightTexel r;
  r.valid = false;
  float depth = texelFetch(uLightDepth, t, 0).r;
  if (!(depth < 1.0)) return r;
  LightView v = lightViews[t.z];
  float G = float(textureSize(uLightDepth, 0).x);
  vec2 ndc = (vec2(t.xy) + 0.5) / G * 2.0 - 1.0;
  vec4 w = v.worldFromClip * vec4(ndc, depth * 2.0 - 1.0, 1.0);
  r.p = w.xyz / w.w;
  LightSample s = sampleLight(int(v.info.x), r.p);
  float texel = 2.0 * v.info.y / G;  // at distance 1 (perspective) or in world units
  if (v.info.z > 0.5) {
    r.fluxIn = s.radiance * texel * texel;
  } else {
    vec2 q = ndc * v.info.y;
    float c = inversesqrt(1.0 + dot(q, q));
    r.fluxIn = s.radiance * (s.dist * s.dist) * (texel * texel * c * c * c);
  }
  r.wi = s.wi;
  vec4 base = texelFetch(uLightBase, t, 0);
  vec4 nn = texelFetch(uLightNormal, t, 0);
  uvec4 m = texelFetch(uLightMaterial, t, 0);
  vec3 emission;
  r.mat = gbufferMaterial(base.rgb, m, emission);
  r.materialIndex = m.w;
  r.radius = base.a;
  r.n = nn.w > 0.0 ? normalize(nn.xyz) : s.wi;
  if (dot(r.n, s.wi) < 0.0) r.n = -r.n;  // two-sided, as the reference
  r.valid = any(greaterThan(r.fluxIn, vec3(0.0)));
  return r;
}

// What the paper samples VPLs by: the reflected flux's luminance, times a weight favouring
// glossy surfaces (their VPLs carry sharp lobes and need to be denser; the paper's "specular
// power" factor): 1 + 4 (1 - roughness)^2 on GGX and principled materials.
float texelImportance(LightTexel t) {
  if (!t.valid) return 0.0;
  vec3 albedo = albedoEstimate(t.mat);
  float specWeight = t.mat.type == NL_MATERIAL_LAMBERT ? 0.0 : 4.0 * (1.0 - t.mat.roughness) * (1.0 - t.mat.roughness);
  return luminance(t.fluxIn * albedo) * (1.0 + specWeight);
}
