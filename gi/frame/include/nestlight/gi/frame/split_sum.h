// The environment's light on glossy lobes in the GI frame, by the split-sum approximation
// (Karis 2013, "Real Shading in Unreal Engine 4", SIGGRAPH course notes; as Filament's image-based
// lighting does): the integral of L(l) f(v, l) cos over the hemisphere is taken as the product of
// the environment prefiltered by the GGX lobe (shaders/gi/common/environment_prefilter.comp) and
// the BRDF's directional albedo for F0 = 0 and F0 = 1, tabulated here over (n.v, roughness).
//
// The table integrates exactly the GGX lobe that gi/core's materials and shaders/gi/common/
// brdf.glsl evaluate (alpha = roughness^2 clamped at 1e-3, Smith's height-correlated masking-
// shadowing, Schlick's Fresnel), so F0 A + B is that lobe's directional albedo: under a constant
// sky the split sum is exact for it, whatever the roughness.
#pragma once

#include <vector>

namespace nestlight::gi {

struct SplitSumTable {
  int size = 0;  // size x size entries
  // (A, B) per entry, row-major: entry (i, j) at n.v = (i + 0.5) / size, roughness =
  // (j + 0.5) / size, so a GL texture of it sampled linearly at (n.v, roughness) interpolates
  // between entry centres.
  std::vector<float> ab;
  float a(int i, int j) const { return ab[2 * (size_t(j) * size + i)]; }
  float b(int i, int j) const { return ab[2 * (size_t(j) * size + i) + 1]; }
};

// The directional albedo of the GGX lobe at one (n.v, roughness), split as F0 A + B: `samples`
// half vectors from a Hammersley set, importance-sampled by D(h) (n.h).
void splitSumEntry(float nDotV, float roughness, int samples, float* a, float* b);

SplitSumTable splitSumTable(int size = 32, int samples = 1024);

}  // namespace nestlight::gi
