// The frame's lights (NL_SSBO_LIGHTS) and their shadow maps (one 2D array, NL_SSBO_SHADOW_VIEWS
// holding each layer's clip-from-world): delta lights as gi/reference's next-event estimation
// treats them (inverse-square point and spot lights, the spot's smoothstep falloff between the
// outer and inner cones, directional lights as irradiance), visibility from the shadow maps.
#include "../../interface/frame_interface.glsl"
layout(std430, binding = NL_SSBO_LIGHTS) readonly buffer Lights { LightRecord lights[]; };
layout(std430, binding = NL_SSBO_SHADOW_VIEWS) readonly buffer ShadowViews { mat4 shadowViews[]; };
layout(binding = 4) uniform sampler2DArrayShadow uShadowMaps;

struct LightSample {
  vec3 wi;       // towards the light
  vec3 radiance; // incident: intensity / d^2 (x falloff), or irradiance (directional)
  float dist;    // to the light; 1e30 for directional
};

LightSample sampleLight(int i, vec3 p) {
  LightRecord l = lights[i];
  LightSample s;
  int type = int(l.position.w);
  if (type == NL_LIGHT_DIRECTIONAL) {
    s.wi = -normalize(l.direction.xyz);
    s.radiance = l.intensity.rgb;
    s.dist = 1e30;
    return s;
  }
  vec3 toLight = l.position.xyz - p;
  float d2 = dot(toLight, toLight);
  s.dist = sqrt(d2);
  s.wi = d2 > 0.0 ? toLight / s.dist : vec3(0.0, 0.0, 1.0);
  s.radiance = d2 > 0.0 ? l.intensity.rgb / d2 : vec3(0.0);
  if (type == NL_LIGHT_SPOT) {
    float cosTheta = dot(-s.wi, normalize(l.direction.xyz));
    float cosOuter = l.cone.x, cosInner = l.cone.y;
    float t = clamp((cosTheta - cosOuter) / max(cosInner - cosOuter, 1e-6), 0.0, 1.0);
    s.radiance *= cosTheta >= cosInner ? 1.0 : (cosTheta <= cosOuter ? 0.0 : t * t * (3.0 - 2.0 * t));
  }
  return s;
}

// The shadow-map layer of light i that sees direction -wi (point lights: the cube face).
int shadowLayer(int i, vec3 wi) {
  LightRecord l = lights[i];
  int first = int(l.shadow.x);
  if (first < 0 || int(l.position.w) != NL_LIGHT_POINT) return first;
  vec3 d = -wi, a = abs(d);  // from the light to the point
  int face = a.x >= a.y && a.x >= a.z ? (d.x > 0.0 ? 0 : 1) : (a.y >= a.z ? (d.y > 0.0 ? 2 : 3) : (d.z > 0.0 ? 4 : 5));
  return first + face;
}

// Fraction of light i reaching p (normal n, facing the light). The lookup point moves along the
// normal (normal-offset shadows) by up to 2 shadow texels, more where the light grazes, and by
// the splat radius of a scan point (a splat is flat in the light's view, so its neighbours
// within a radius lie behind it): a surface does not shadow itself. A 3 x 3 PCF of
// hardware-filtered compares softens the texel edges.
// `maps`: the frame's shadow maps, or another set drawn from the same light views (differential
// rendering's, without the inserted meshes).
float visibilityIn(sampler2DArrayShadow maps, int i, vec3 p, vec3 n, float splatRadius, LightSample s) {
  int layer = shadowLayer(i, s.wi);
  if (layer < 0) return 1.0;
  LightRecord l = lights[i];
  bool ortho = int(l.position.w) == NL_LIGHT_DIRECTIONAL;
  float texel = ortho ? l.shadow.y : l.shadow.y * s.dist;
  float cosL = clamp(dot(n, s.wi), 0.0, 1.0);
  vec3 q = p + n * (1.5 * texel * sqrt(max(1.0 - cosL * cosL, 0.0)) + 0.5 * texel + splatRadius) + s.wi * l.cone.z;
  vec4 clip = shadowViews[layer] * vec4(q, 1.0);
  if (clip.w <= 0.0) return 1.0;
  vec3 ndc = clip.xyz / clip.w;
  if (any(greaterThan(abs(ndc.xy), vec2(1.0)))) return 1.0;  // outside the light's view: lit
  vec2 uv = ndc.xy * 0.5 + 0.5;
  float ref = clamp(ndc.z * 0.5 + 0.5, 0.0, 1.0);
  vec2 size = vec2(textureSize(maps, 0).xy);
  float sum = 0.0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      sum += texture(maps, vec4(uv + vec2(dx, dy) / size, float(layer), ref));
  return sum / 9.0;
}

float visibility(int i, vec3 p, vec3 n, float splatRadius, LightSample s) {
  return visibilityIn(uShadowMaps, i, p, n, splatRadius, s);
}
