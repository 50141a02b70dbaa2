// BSDFs of inserted objects. Lambert; GGX microfacet reflection (Walter, Marschner, Li, Torrance
// 2007, "Microfacet Models for Refraction through Rough Surfaces": the reflection term
// F G D / (4 cos_o cos_i) and GGX's D and Smith G1) with Smith's height-correlated masking-
// shadowing G2 = 1 / (1 + Lambda_o + Lambda_i) (Heitz 2014, "Understanding the Masking-Shadowing
// Function in Microfacet-Based BRDFs") and visible-normal sampling (Heitz 2018, "Sampling the GGX
// Distribution of Visible Normals", JCGT 7(4)); Schlick's Fresnel approximation (Schlick 1994);
// the Disney principled BRDF subset of Burley 2012 ("Physically-Based Shading at Disney":
// diffuse with retro-reflection, sheen, specular with tint, a GTR1 clearcoat).
//
// Deviations, all so that the white furnace holds (directional albedo <= 1 at every angle):
// - The diffuse part (Lambert or Burley, and sheen) lies under the dielectric specular layer: it
//   is weighted by (1 - F(cos theta_o)) (1 - F(cos theta_i)) with the dielectric F0 (0.04 for
//   GGX, 0.08 specular tint for Principled). Adding an unweighted Lambert lobe to a specular
//   one reflects 1 + F of the light; Burley's diffuse alone, at roughness 1, reflects 1.04
//   head-on and 1.5 at cos theta_o = 0.03 (measured by quadrature). The weight is symmetric,
//   so reciprocity holds. The price: a white dielectric reflects ~0.92 head-on, not 1.
// - The clearcoat attenuates what lies under it by (1 - c F_c(cos theta_o)) (1 - c F_c(cos
//   theta_i)), c = 0.25 clearcoat being Burley's coat strength.
// - The clearcoat's masking is the same height-correlated Smith term with Burley's fixed
//   alpha 0.25.
// Consequently the Principled BRDF is darker than Burley's at grazing angles.
#include "nestlight/gi/material.h"

#include <algorithm>
#include <cmath>

namespace nestlight::gi {
namespace {

constexpr float kMinAlpha = 1e-3f;
// Directions closer to the horizon than this count as below it. Below ~1e-19 the squares of
// the cosines underflow and the half vector of two grazing directions becomes 0/0; 1e-9 keeps
// every intermediate (D <= 3.2e5, visibility <= 2.5e11, pdfs <= 1e13) well inside float range.
constexpr float kMinCos = 1e-9f;
constexpr float kClearcoatMaskingAlpha = 0.25f;
constexpr float kClearcoatF0 = 0.04f;
constexpr float kClearcoatStrength = 0.25f;
// Every lobe that can reflect keeps at least this share of the samples, so that a crude lobe
// weight (estimated from wo alone) never starves a lobe whose f is not zero.
constexpr float kMinLobeProbability = 0.05f;

float unit(float x, float fallback) {  // NaN -> fallback, clamp to [0, 1]
  return std::isnan(x) ? fallback : std::clamp(x, 0.0f, 1.0f);
}
Rgb unit(const Rgb& c) {
  return {unit(c.r, 0), unit(c.g, 0), unit(c.b, 0)};
}

float pow5(float x) {
  float x2 = x * x;
  return x2 * x2 * x;
}
float schlick(float f0, float cosTheta) {
  return f0 + (1 - f0) * pow5(1 - cosTheta);
}
Rgb schlick(const Rgb& f0, float cosTheta) {
  return f0 + (Rgb(1.0f) - f0) * pow5(1 - cosTheta);
}

// sin^2 from the components: 1 - cos^2 cancels near the normal.
float sin2(const glm::vec3& w) {
  return w.x * w.x + w.y * w.y;
}

// GGX (Trowbridge-Reitz) normal distribution, D(h) = a^2 / (pi (sin^2 + a^2 cos^2)^2), written
// with sin^2 from the components so that a = 1e-3 around the normal keeps its precision.
float ggxD(const glm::vec3& h, float alpha2) {
  float t = sin2(h) + alpha2 * h.z * h.z;
  return alpha2 / (kPi * t * t);
}

// GTR1 (Burley 2012's generalised Trowbridge-Reitz, gamma = 1): the clearcoat's long tails. Its
// 1 + (a^2 - 1) cos^2 is written sin^2 + a^2 cos^2: near the peak the former cancels to 1e-6
// and float keeps only a few bits of it.
float gtr1D(const glm::vec3& h, float alpha2, float logAlpha2) {
  float t = sin2(h) + alpha2 * h.z * h.z;
  return (alpha2 - 1) / (kPi * logAlpha2 * t);
}

// Smith height-correlated G2 / (4 cos_o cos_i), from Lambda(w) = (sqrt(1 + a^2 tan^2) - 1) / 2:
// 1 + Lambda_o + Lambda_i = (sqrt(1 + a^2 tan_o^2) + sqrt(1 + a^2 tan_i^2)) / 2, and multiplying
// through by cos_o cos_i leaves no tangent to overflow at the horizon.
float smithVisibility(const glm::vec3& wo, const glm::vec3& wi, float alpha2) {
  float a = wi.z * std::sqrt(wo.z * wo.z + alpha2 * sin2(wo));
  float b = wo.z * std::sqrt(wi.z * wi.z + alpha2 * sin2(wi));
  return 0.5f / (a + b);
}

// Smith G1(w) / cos(w) = 2 / (cos + sqrt(cos^2 + a^2 sin^2)): the visible-normal pdf's factor.
float smithG1OverCos(const glm::vec3& w, float alpha2) {
  return 2 / (w.z + std::sqrt(w.z * w.z + alpha2 * sin2(w)));
}

glm::vec3 reflect(const glm::vec3& wo, const glm::vec3& h) {
  return 2 * glm::dot(wo, h) * h - wo;
}

// Heitz 2018: the visible normals of a GGX surface are the normals of a hemisphere seen from wo
// once the surface is stretched to alpha = 1; sample the projected disk of that hemisphere (the
// half that is not seen at an angle is squeezed by s), lift onto it and unstretch.
glm::vec3 sampleGgxVisibleNormal(const glm::vec3& wo, float alpha, glm::vec2 u) {
  glm::vec3 v = glm::normalize(glm::vec3(alpha * wo.x, alpha * wo.y, wo.z));
  float len2 = v.x * v.x + v.y * v.y;
  glm::vec3 t1 = len2 > 0 ? glm::vec3(-v.y, v.x, 0) / std::sqrt(len2) : glm::vec3(1, 0, 0);
  glm::vec3 t2 = glm::cross(v, t1);
  float r = std::sqrt(u.x), phi = 2 * kPi * u.y;
  float p1 = r * std::cos(phi), p2 = r * std::sin(phi);
  float s = 0.5f * (1 + v.z);
  p2 = (1 - s) * std::sqrt(std::max(0.0f, 1 - p1 * p1)) + s * p2;
  glm::vec3 n = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0f, 1 - p1 * p1 - p2 * p2)) * v;
  return glm::normalize(glm::vec3(alpha * n.x, alpha * n.y, std::max(0.0f, n.z)));
}

// Sample h with density D_GTR1(h) cos theta_h: its CDF in cos^2 theta_h is
// ln(1 + (a^2 - 1) cos^2) / ln a^2. sin^2 is computed directly: 1 - cos^2 near the peak is
// ~a^2 = 1e-6, which a float near 1 cannot resolve.
glm::vec3 sampleGtr1(float alpha2, glm::vec2 u) {
  float p = std::pow(alpha2, 1 - u.x);
  float s2 = std::clamp((p - alpha2) / (1 - alpha2), 0.0f, 1.0f);
  float c = std::sqrt(1 - s2), s = std::sqrt(s2);
  float phi = 2 * kPi * u.y;
  return {s * std::cos(phi), s * std::sin(phi), c};
}

// The material's parameters resolved once per call into the terms the lobes use.
struct Lobes {
  bool specular = false, burley = false;
  Rgb diffuse{0.0f};       // (1 - metallic) base colour
  Rgb sheen{0.0f};         // (1 - metallic) sheen * C_sheen
  Rgb f0{0.0f};            // specular F0 (metals and dielectrics mixed)
  Rgb f0Dielectric{0.0f};  // the layer the diffuse part lies under
  float roughness = 1, alpha = 1, alpha2 = 1;
  float coat = 0, coatAlpha2 = 0, coatLogAlpha2 = 0;  // 0.25 clearcoat; GTR1 alpha^2, ln alpha^2
};

Lobes resolve(const Material& m) {
  Lobes l;
  Rgb base = unit(m.baseColor);
  if (m.type == MaterialType::Lambert) {
    l.diffuse = base;
    return l;
  }
  float metallic = unit(m.metallic, 0);
  l.specular = true;
  l.roughness = unit(m.roughness, 0.5f);
  l.alpha = std::max(kMinAlpha, l.roughness * l.roughness);
  l.alpha2 = l.alpha * l.alpha;
  l.diffuse = (1 - metallic) * base;
  if (m.type == MaterialType::GGX) {
    l.f0Dielectric = Rgb(0.04f);
  } else {
    l.burley = true;
    float lum = luminance(base);
    Rgb tint = lum > 0 ? base / lum : Rgb(1.0f);  // hue and saturation without luminance
    l.f0Dielectric = glm::min(Rgb(1.0f), 0.08f * unit(m.specular, 0.5f) *
                                             glm::mix(Rgb(1.0f), tint, unit(m.specularTint, 0)));
    l.sheen =
        (1 - metallic) * unit(m.sheen, 0) * glm::mix(Rgb(1.0f), tint, unit(m.sheenTint, 0.5f));
    l.coat = kClearcoatStrength * unit(m.clearcoat, 0);
    float coatAlpha = glm::mix(0.1f, 0.001f, unit(m.clearcoatGloss, 1));
    l.coatAlpha2 = coatAlpha * coatAlpha;
    l.coatLogAlpha2 = std::log(l.coatAlpha2);
  }
  l.f0 = glm::mix(l.f0Dielectric, base, metallic);
  return l;
}

struct LobeProbabilities {
  float diffuse = 1, specular = 0, coat = 0;
};

// Each lobe's share of the reflected energy, estimated from wo alone (Fresnel at cos theta_o,
// the albedo of what lies beneath) so that pdfBsdf can recompute exactly the mixture that
// sampleBsdf drew from.
LobeProbabilities lobeProbabilities(const Lobes& l, const glm::vec3& wo) {
  LobeProbabilities p;
  if (!l.specular) return p;
  float coatF = l.coat * schlick(kClearcoatF0, wo.z);
  Rgb below = (1 - coatF) * (Rgb(1.0f) - schlick(l.f0Dielectric, wo.z));
  float wd = glm::dot(below * (l.diffuse + 0.25f * l.sheen), Rgb(1.0f / 3));
  float ws = (1 - coatF) * glm::dot(schlick(l.f0, wo.z), Rgb(1.0f / 3));
  float wc = coatF;
  bool hasDiffuse = glm::dot(l.diffuse + l.sheen, Rgb(1.0f)) > 0;
  bool hasCoat = l.coat > 0;
  float total = wd + ws + wc;
  if (!(total > 0)) {  // e.g. a black metal seen head-on: F0 = 0; any positive split is unbiased
    wd = hasDiffuse ? 1.0f : 0.0f;
    ws = 1;
    wc = hasCoat ? 1.0f : 0.0f;
    total = wd + ws + wc;
  }
  // Each lobe that can reflect gets the floor, and the rest of the samples in proportion.
  const int lobes = 1 + int(hasDiffuse) + int(hasCoat);
  const float k = (1 - float(lobes) * kMinLobeProbability) / total;
  p.diffuse = hasDiffuse ? kMinLobeProbability + k * wd : 0;
  p.specular = kMinLobeProbability + k * ws;
  p.coat = hasCoat ? kMinLobeProbability + k * wc : 0;
  return p;
}

struct EvalPdf {
  Rgb f{0.0f};
  float pdf = 0;
};

bool above(const glm::vec3& w) {
  return w.z > kMinCos;
}  // false for NaN too

// f and the mixture pdf share the half vector and D; `want` skips the half not asked for
// (eval and pdf are called once per path vertex each, by MIS).
enum Want { kF = 1, kPdf = 2 };

EvalPdf evalAndPdf(const Lobes& l, const glm::vec3& wo, const glm::vec3& wi, int want = kF | kPdf) {
  EvalPdf r;
  if (!above(wo) || !above(wi)) return r;
  if (!l.specular) {
    r.f = l.diffuse * kInvPi;
    r.pdf = wi.z * kInvPi;
    return r;
  }
  glm::vec3 h = glm::normalize(wo + wi);  // |wo + wi| >= wo.z + wi.z > 2e-9
  float cosD = std::clamp(glm::dot(wi, h), 0.0f, 1.0f);
  float d = ggxD(h, l.alpha2);
  float dc = l.coat > 0 ? gtr1D(h, l.coatAlpha2, l.coatLogAlpha2) : 0.0f;

  if (want & kF) {
    Rgb diffuse = l.diffuse * kInvPi;
    if (l.burley) {
      // Burley's retro-reflection: a Schlick-like factor towards Fd90 at grazing o and i.
      float fd90 = 0.5f + 2 * l.roughness * cosD * cosD;
      float fo = 1 + (fd90 - 1) * pow5(1 - wo.z), fi = 1 + (fd90 - 1) * pow5(1 - wi.z);
      diffuse = diffuse * (fo * fi) + l.sheen * pow5(1 - cosD);
    }
    Rgb transmitted =
        (Rgb(1.0f) - schlick(l.f0Dielectric, wo.z)) * (Rgb(1.0f) - schlick(l.f0Dielectric, wi.z));
    Rgb below =
        diffuse * transmitted + schlick(l.f0, cosD) * (d * smithVisibility(wo, wi, l.alpha2));
    if (l.coat > 0) {
      float coatO = l.coat * schlick(kClearcoatF0, wo.z),
            coatI = l.coat * schlick(kClearcoatF0, wi.z);
      r.f = below * ((1 - coatO) * (1 - coatI)) +
            Rgb(l.coat * dc * schlick(kClearcoatF0, cosD) *
                smithVisibility(wo, wi, kClearcoatMaskingAlpha * kClearcoatMaskingAlpha));
    } else {
      r.f = below;
    }
  }
  if (want & kPdf) {
    LobeProbabilities p = lobeProbabilities(l, wo);
    r.pdf = p.diffuse * wi.z * kInvPi + p.specular * d * smithG1OverCos(wo, l.alpha2) * 0.25f;
    // cosD = |wo + wi| / 2 > 1e-9: the h-to-wi Jacobian 1 / (4 cosD) stays finite.
    if (p.coat > 0) r.pdf += p.coat * dc * h.z / (4 * cosD);
  }
  return r;
}

}  // namespace

Rgb evalBsdf(const Material& m, const glm::vec3& wo, const glm::vec3& wi) {
  return evalAndPdf(resolve(m), wo, wi, kF).f;
}

float pdfBsdf(const Material& m, const glm::vec3& wo, const glm::vec3& wi) {
  return evalAndPdf(resolve(m), wo, wi, kPdf).pdf;
}

std::optional<BsdfSample> sampleBsdf(const Material& m, const glm::vec3& wo, glm::vec2 u,
                                     float uLobe) {
  if (!above(wo)) return std::nullopt;
  Lobes l = resolve(m);
  u = glm::clamp(u, glm::vec2(0.0f), glm::vec2(kOneMinusEpsilon));
  glm::vec3 wi;
  LobeProbabilities p = lobeProbabilities(l, wo);
  if (uLobe < p.diffuse) {
    wi = sampleCosineHemisphere(u);
  } else if (uLobe < p.diffuse + p.specular || p.coat == 0) {
    wi = reflect(wo, sampleGgxVisibleNormal(wo, l.alpha, u));
  } else {
    glm::vec3 h = sampleGtr1(l.coatAlpha2, u);
    // A normal facing away from wo reflects below the surface; pdfBsdf's half vector
    // normalize(wo + wi) of an accepted wi always faces wo, so rejecting keeps the two equal.
    if (!(glm::dot(wo, h) > 0)) return std::nullopt;
    wi = reflect(wo, h);
  }
  if (!above(wi)) return std::nullopt;
  EvalPdf e = evalAndPdf(l, wo, wi);
  if (!(e.pdf > 0) || !std::isfinite(e.pdf)) return std::nullopt;
  return BsdfSample{wi, e.f, e.pdf};
}

Rgb directionalAlbedo(const Material& m, const glm::vec3& wo, int samples, uint64_t seed) {
  if (samples <= 0 || !above(wo)) return Rgb(0.0f);
  Rng rng(seed);
  glm::dvec3 sum(0.0);
  for (int i = 0; i < samples; ++i) {
    glm::vec2 u = rng.uniform2();
    float uLobe = rng.uniform();
    if (auto s = sampleBsdf(m, wo, u, uLobe)) sum += glm::dvec3(s->f * (s->wi.z / s->pdf));
  }
  return Rgb(sum / double(samples));
}

const char* materialTypeName(MaterialType t) {
  switch (t) {
    case MaterialType::Lambert:
      return "lambert";
    case MaterialType::GGX:
      return "ggx";
    case MaterialType::Principled:
      return "principled";
  }
  return "unknown";
}

}  // namespace nestlight::gi
