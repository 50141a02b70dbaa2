// Sampling the BSDFs of brdf.glsl and their densities, with the same lobes, lobe choice and
// densities as gi/core's sampleBsdf and pdfBsdf (material.cpp), so a GPU estimator's weights and
// the reference's agree: cosine-weighted diffuse; GGX visible normals (Heitz 2018, "Sampling the
// GGX Distribution of Visible Normals"); GTR1 half vectors for the clearcoat (Burley 2012).
// Local shading frame as brdf.glsl: n = +z, wo towards the viewer; pdfs per solid angle of wi.
#include "brdf.glsl"

const float kMinLobeProbability = 0.05;

struct LobeChoice {
  float diffuse, specular, coat;  // each lobe's share of the samples
  Lobes l;
};

// Each lobe's share of the samples, from wo alone (material.cpp's lobeProbabilities).
LobeChoice lobeChoice(MaterialParams m, vec3 wo) {
  LobeChoice c;
  c.l = resolveLobes(m);
  c.diffuse = 1.0, c.specular = 0.0, c.coat = 0.0;
  if (c.l.lambert) return c;
  float coatF = c.l.coat * schlick(0.04, wo.z);
  vec3 below = (1.0 - coatF) * (vec3(1.0) - schlick(c.l.f0Dielectric, wo.z));
  float wd = dot(below * (c.l.diffuseAlbedo + 0.25 * c.l.sheen), vec3(1.0 / 3.0));
  float ws = (1.0 - coatF) * dot(schlick(c.l.f0, wo.z), vec3(1.0 / 3.0));
  float wc = coatF;
  bool hasDiffuse = dot(c.l.diffuseAlbedo + c.l.sheen, vec3(1.0)) > 0.0;
  bool hasCoat = c.l.coat > 0.0;
  float total = wd + ws + wc;
  if (!(total > 0.0)) {
    wd = hasDiffuse ? 1.0 : 0.0;
    ws = 1.0;
    wc = hasCoat ? 1.0 : 0.0;
    total = wd + ws + wc;
  }
  float lobes = 1.0 + (hasDiffuse ? 1.0 : 0.0) + (hasCoat ? 1.0 : 0.0);
  float k = (1.0 - lobes * kMinLobeProbability) / total;
  c.diffuse = hasDiffuse ? kMinLobeProbability + k * wd : 0.0;
  c.specular = kMinLobeProbability + k * ws;
  c.coat = hasCoat ? kMinLobeProbability + k * wc : 0.0;
  return c;
}

float smithG1OverCos(vec3 w, float a2) { return 2.0 / (w.z + sqrt(w.z * w.z + a2 * sin2(w))); }

float pdfBsdf(MaterialParams m, vec3 wo, vec3 wi) {
  if (!(wo.z > kMinCos) || !(wi.z > kMinCos)) return 0.0;
  LobeChoice c = lobeChoice(m, wo);
  if (m.type == NL_MATERIAL_LAMBERT) return wi.z * kInvPi;
  vec3 h = normalize(wo + wi);
  float cosD = clamp(dot(wi, h), 0.0, 1.0);
  float pdf = c.diffuse * wi.z * kInvPi + c.specular * ggxD(h, c.l.a2) * smithG1OverCos(wo, c.l.a2) * 0.25;
  if (c.coat > 0.0) pdf += c.coat * gtr1D(h, c.l.coatA2, c.l.coatLogA2) * h.z / (4.0 * max(cosD, 1e-9));
  return pdf;
}

vec3 sampleCosineHemisphereGl(vec2 u) {
  float r = sqrt(u.x), phi = 2.0 * kPi * u.y;
  vec2 d = r * vec2(cos(phi), sin(phi));
  return vec3(d, sqrt(max(0.0, 1.0 - dot(d, d))));
}

vec3 sampleGgxVisibleNormal(vec3 wo, float alpha, vec2 u) {
  vec3 v = normalize(vec3(alpha * wo.x, alpha * wo.y, wo.z));
  float len2 = v.x * v.x + v.y * v.y;
  vec3 t1 = len2 > 0.0 ? vec3(-v.y, v.x, 0.0) / sqrt(len2) : vec3(1.0, 0.0, 0.0);
  vec3 t2 = cross(v, t1);
  float r = sqrt(u.x), phi = 2.0 * kPi * u.y;
  float p1 = r * cos(phi), p2 = r * sin(phi);
  float s = 0.5 * (1.0 + v.z);
  p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * p2;
  vec3 n = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * v;
  return normalize(vec3(alpha * n.x, alpha * n.y, max(0.0, n.z)));
}

vec3 sampleGtr1(float a2, vec2 u) {
  float p = pow(a2, 1.0 - u.x);
  float s2 = clamp((p - a2) / (1.0 - a2), 0.0, 1.0);
  float c = sqrt(1.0 - s2), s = sqrt(s2);
  float phi = 2.0 * kPi * u.y;
  return vec3(s * cos(phi), s * sin(phi), c);
}

// A direction drawn from the BSDF's mixture of lobes (`uLobe` picks the lobe); false when wo is
// below the surface or the drawn direction is (the sample then counts as zero).
bool sampleBsdf(MaterialParams m, vec3 wo, vec2 u, float uLobe, out vec3 wi) {
  wi = vec3(0.0, 0.0, 1.0);
  if (!(wo.z > kMinCos)) return false;
  u = clamp(u, vec2(0.0), vec2(0.99999994));
  LobeChoice c = lobeChoice(m, wo);
  if (uLobe < c.diffuse) {
    wi = sampleCosineHemisphereGl(u);
  } else if (uLobe < c.diffuse + c.specular || c.coat == 0.0) {
    wi = reflect(-wo, sampleGgxVisibleNormal(wo, c.l.alpha, u));
  } else {
    vec3 h = sampleGtr1(c.l.coatA2, u);
    if (!(dot(wo, h) > 0.0)) return false;
    wi = reflect(-wo, h);
  }
  return wi.z > kMinCos;
}
