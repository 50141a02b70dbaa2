// The BSDFs of gi/core's materials (nestlight/gi/material.h, material.cpp), evaluated on the GPU
// with the same terms, so a GPU method and the reference shade a material identically: Lambert;
// GGX (Walter et al. 2007, "Microfacet Models for Refraction through Rough Surfaces") with
// Smith's height-correlated masking-shadowing (Heitz 2014) and Schlick's Fresnel, its diffuse
// part under the dielectric layer; the Disney principled subset (Burley 2012, "Physically-Based
// Shading at Disney": retro-reflective diffuse, sheen, tinted specular, GTR1 clearcoat).
// Local shading frame: n = +z, wo towards the viewer, wi towards the light; f without the cosine.
#include "../../interface/frame_interface.glsl"

const float kPi = 3.14159265358979;
const float kInvPi = 0.318309886183791;
const float kMinCos = 1e-9;

struct MaterialParams {
  int type;            // NL_MATERIAL_*
  vec3 baseColor;      // linear, [0, 1]
  float roughness, metallic;
  float specular, specularTint, sheen, sheenTint, clearcoat, clearcoatGloss;
};

float pow5(float x) { float x2 = x * x; return x2 * x2 * x; }
float schlick(float f0, float c) { return f0 + (1.0 - f0) * pow5(1.0 - c); }
vec3 schlick(vec3 f0, float c) { return f0 + (vec3(1.0) - f0) * pow5(1.0 - c); }
float sin2(vec3 w) { return w.x * w.x + w.y * w.y; }
float ggxD(vec3 h, float a2) { float t = sin2(h) + a2 * h.z * h.z; return a2 / (kPi * t * t); }
float gtr1D(vec3 h, float a2, float logA2) { float t = sin2(h) + a2 * h.z * h.z; return (a2 - 1.0) / (kPi * logA2 * t); }
float smithVisibility(vec3 wo, vec3 wi, float a2) {
  float a = wi.z * sqrt(wo.z * wo.z + a2 * sin2(wo));
  float b = wo.z * sqrt(wi.z * wi.z + a2 * sin2(wi));
  return 0.5 / (a + b);
}
float luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

// The material's parameters resolved into the terms the lobes use (material.cpp's resolve()):
// shared by evaluation and sampling (brdf_sample.glsl).
struct Lobes {
  bool lambert, burley;
  vec3 base, diffuseAlbedo, sheen, f0, f0Dielectric;
  float roughness, alpha, a2, coat, coatA2, coatLogA2;
};

Lobes resolveLobes(MaterialParams m) {
  Lobes l;
  l.base = clamp(m.baseColor, 0.0, 1.0);
  l.lambert = m.type == NL_MATERIAL_LAMBERT;
  l.burley = m.type == NL_MATERIAL_PRINCIPLED;
  float metallic = l.lambert ? 0.0 : clamp(m.metallic, 0.0, 1.0);
  l.roughness = clamp(m.roughness, 0.0, 1.0);
  l.alpha = max(1e-3, l.roughness * l.roughness), l.a2 = l.alpha * l.alpha;
  l.diffuseAlbedo = (1.0 - metallic) * l.base;
  l.f0Dielectric = vec3(0.04), l.sheen = vec3(0.0);
  l.coat = 0.0, l.coatA2 = 0.0, l.coatLogA2 = 0.0;
  if (l.burley) {
    float lum = luminance(l.base);
    vec3 tint = lum > 0.0 ? l.base / lum : vec3(1.0);
    l.f0Dielectric = min(vec3(1.0), 0.08 * clamp(m.specular, 0.0, 1.0) * mix(vec3(1.0), tint, clamp(m.specularTint, 0.0, 1.0)));
    l.sheen = (1.0 - metallic) * clamp(m.sheen, 0.0, 1.0) * mix(vec3(1.0), tint, clamp(m.sheenTint, 0.0, 1.0));
    l.coat = 0.25 * clamp(m.clearcoat, 0.0, 1.0);
    float coatAlpha = mix(0.1, 0.001, clamp(m.clearcoatGloss, 0.0, 1.0));
    l.coatA2 = coatAlpha * coatAlpha;
    l.coatLogA2 = log(l.coatA2);
  }
  l.f0 = mix(l.f0Dielectric, l.base, metallic);
  return l;
}

vec3 evalBsdf(MaterialParams m, vec3 wo, vec3 wi) {
  if (!(wo.z > kMinCos) || !(wi.z > kMinCos)) return vec3(0.0);
  Lobes l = resolveLobes(m);
  if (l.lambert) return l.base * kInvPi;
  vec3 h = normalize(wo + wi);
  float cosD = clamp(dot(wi, h), 0.0, 1.0);
  vec3 diffuse = l.diffuseAlbedo * kInvPi;
  if (l.burley) {
    float fd90 = 0.5 + 2.0 * l.roughness * cosD * cosD;
    float fo = 1.0 + (fd90 - 1.0) * pow5(1.0 - wo.z), fi = 1.0 + (fd90 - 1.0) * pow5(1.0 - wi.z);
    diffuse = diffuse * (fo * fi) + l.sheen * pow5(1.0 - cosD);
  }
  vec3 transmitted = (vec3(1.0) - schlick(l.f0Dielectric, wo.z)) * (vec3(1.0) - schlick(l.f0Dielectric, wi.z));
  vec3 below = diffuse * transmitted + schlick(l.f0, cosD) * (ggxD(h, l.a2) * smithVisibility(wo, wi, l.a2));
  if (l.coat > 0.0) {
    float coatO = l.coat * schlick(0.04, wo.z), coatI = l.coat * schlick(0.04, wi.z);
    return below * ((1.0 - coatO) * (1.0 - coatI)) +
           vec3(l.coat * gtr1D(h, l.coatA2, l.coatLogA2) * schlick(0.04, cosD) * smithVisibility(wo, wi, 0.0625));
  }
  return below;
}

// An orthonormal frame around a unit normal (Duff et al. 2017, "Building an Orthonormal Basis,
// Revisited"), as gi::Frame.
mat3 frameFromNormal(vec3 n) {
  float s = n.z >= 0.0 ? 1.0 : -1.0;
  float a = -1.0 / (s + n.z);
  float b = n.x * n.y * a;
  vec3 t = vec3(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
  vec3 bt = vec3(b, s + n.y * n.y * a, -n.y);
  return mat3(t, bt, n);  // columns: local -> world
}
