// Materials of inserted objects and their BSDFs: Lambert, GGX microfacet (Walter et al. 2007,
// with Heitz 2018 visible-normal sampling) with roughness and metallic, and a subset of the
// Disney principled BRDF (Burley 2012: base colour, metallic, roughness, specular, specular
// tint, sheen, sheen tint, clearcoat, clearcoat gloss; no subsurface, anisotropy or
// transmission).
//
// Every function works in the local shading frame: the normal is +z, `wo` points away from the
// surface towards the viewer, `wi` towards the light. eval() returns f(wo, wi) without the
// cosine; pdf() is per solid angle of wi. Directions below the surface give f = 0, pdf = 0.
#pragma once

#include <optional>
#include <string>

#include "nestlight/gi/sampling.h"

namespace nestlight::gi {

enum class MaterialType { Lambert, GGX, Principled };

struct Material {
  MaterialType type = MaterialType::Lambert;
  Rgb baseColor{0.8f};
  float roughness = 0.5f;  // perceptual roughness; GGX alpha = roughness^2, clamped >= 1e-3
  float metallic = 0;
  float specular = 0.5f;  // Principled: F0 of dielectrics = 0.08 * specular
  float specularTint = 0;
  float sheen = 0;
  float sheenTint = 0.5f;
  float clearcoat = 0;
  float clearcoatGloss = 1;
  Rgb emission{0.0f};  // emitted radiance (W sr^-1 m^-2 per channel)
  std::string name;
};

struct BsdfSample {
  glm::vec3 wi{0.0f};
  Rgb f{0.0f};    // eval(wo, wi)
  float pdf = 0;  // pdf(wo, wi), solid angle
};

Rgb evalBsdf(const Material& m, const glm::vec3& wo, const glm::vec3& wi);
float pdfBsdf(const Material& m, const glm::vec3& wo, const glm::vec3& wi);
// `u` picks the direction, `uLobe` the lobe. Returns nothing when wo is below the surface or
// the sampled direction is.
std::optional<BsdfSample> sampleBsdf(const Material& m, const glm::vec3& wo, glm::vec2 u,
                                     float uLobe);

// The directional albedo: integral of f cos over the hemisphere for `wo` (Monte Carlo with
// `samples` BSDF samples, seeded). <= 1 for an energy-conserving BSDF; the white-furnace test.
Rgb directionalAlbedo(const Material& m, const glm::vec3& wo, int samples, uint64_t seed = 1);

const char* materialTypeName(MaterialType t);

}  // namespace nestlight::gi
