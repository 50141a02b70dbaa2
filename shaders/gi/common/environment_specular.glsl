// The environment's unshadowed light on a material's glossy lobes by the split sum (Karis 2013,
// "Real Shading in Unreal Engine 4"): the sky prefiltered by the GGX lobe at the reflected
// direction (environment_prefilter.comp, one roughness per mip level) times the lobe's
// directional albedo F0 A + B (nestlight/gi/frame/split_sum.h's table). Roughness between 0 and
// the first prefiltered level blends with the map itself, so a mirror reflects at the map's
// resolution. Needs brdf.glsl and environment.glsl.
layout(binding = 6) uniform sampler2D uEnvPrefiltered;  // level k: roughness (k + 1) / levels
layout(binding = 7) uniform sampler2D uSplitSum;        // (A, B) over (n.v, roughness)
uniform int uEnvPrefilteredLevels;

vec2 environmentUv(vec3 d) {
  float u = (atan(d.y, d.x) - uEnvRotation) / (2.0 * kPi);
  return vec2(u - floor(u), clamp(atan(length(d.xy), d.z) / kPi, 0.0, 1.0));
}

// The prefiltered sky along r for `roughness`.
vec3 prefilteredEnvironment(vec3 r, float roughness) {
  vec2 uv = environmentUv(r);
  float level = roughness * float(uEnvPrefilteredLevels) - 1.0;
  if (level >= 0.0) return textureLod(uEnvPrefiltered, uv, level).rgb;
  vec3 mirror = textureLod(uEnvironment, uv, 0.0).rgb * uEnvScale;
  return mix(mirror, textureLod(uEnvPrefiltered, uv, 0.0).rgb, level + 1.0);
}

vec2 splitSum(float nDotV, float roughness) {
  return texture(uSplitSum, vec2(clamp(nDotV, 0.0, 1.0), clamp(roughness, 0.0, 1.0))).rg;
}

// What direct light adds for the sky on every lobe of `mat` at normal n (facing wo): the
// diffuse lobe's irradiance (spherical harmonics) under the dielectric layer, the specular lobe
// and the clearcoat by the split sum. Lambert is the diffuse term alone, exactly; the principled
// material's retro-reflection and sheen are left out (under a smooth sky the first averages
// close to Lambert's and the second is a grazing rim).
vec3 environmentLight(MaterialParams mat, vec3 n, vec3 wo) {
  Lobes l = resolveLobes(mat);
  vec3 E = irradiance(n);
  if (l.lambert) return l.base * kInvPi * E;
  float nv = max(dot(n, wo), 1e-4);
  vec3 r = reflect(-wo, n);
  // The diffuse part lies under the dielectric interface: transmitted towards the viewer and,
  // for light from every direction, 1 - F0 - (1 - F0) / 21 on average over the cosine-weighted
  // hemisphere (the integral of Schlick's (1 - cos)^5 against 2 cos is 1 / 21).
  vec3 f0d = l.f0Dielectric;
  vec3 transmitted = (vec3(1.0) - schlick(f0d, nv)) * (vec3(1.0) - f0d - (vec3(1.0) - f0d) / 21.0);
  vec3 diffuse = l.diffuseAlbedo * kInvPi * E * transmitted;
  vec2 ab = splitSum(nv, l.roughness);
  vec3 specular = prefilteredEnvironment(r, l.roughness) * (l.f0 * ab.x + ab.y);
  vec3 below = diffuse + specular;
  if (l.coat <= 0.0) return below;
  // The clearcoat's GTR1 lobe is read as GGX of the same alpha: its tail is longer, its mean
  // close.
  float coatRoughness = sqrt(sqrt(l.coatA2));
  vec2 cab = splitSum(nv, coatRoughness);
  float coatF = l.coat * schlick(0.04, nv);
  return below * (1.0 - coatF) * (1.0 - coatF) +
         l.coat * prefilteredEnvironment(r, coatRoughness) * (0.04 * cab.x + cab.y);
}
