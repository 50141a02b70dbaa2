// The split-sum table (Karis 2013, "Real Shading in Unreal Engine 4", section "Image Based
// Lighting"): the GGX lobe's directional albedo split into the terms of F0 and of 1 under
// Schlick's Fresnel, F = F0 (1 - Fc) + Fc with Fc = (1 - v.h)^5.
#include "nestlight/gi/frame/split_sum.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace nestlight::gi {

namespace {

// Van der Corput's radical inverse in base 2: the Hammersley set's second coordinate.
double radicalInverse2(uint32_t i) {
  i = (i << 16u) | (i >> 16u);
  i = ((i & 0x55555555u) << 1u) | ((i & 0xAAAAAAAAu) >> 1u);
  i = ((i & 0x33333333u) << 2u) | ((i & 0xCCCCCCCCu) >> 2u);
  i = ((i & 0x0F0F0F0Fu) << 4u) | ((i & 0xF0F0F0F0u) >> 4u);
  i = ((i & 0x00FF00FFu) << 8u) | ((i & 0xFF00FF00u) >> 8u);
  return double(i) * 2.3283064365386963e-10;
}

}  // namespace

void splitSumEntry(float nDotV, float roughness, int samples, float* a, float* b) {
  // The lobe as brdf.glsl resolves it.
  const double alpha = std::max(1e-3, double(roughness) * roughness), a2 = alpha * alpha;
  const double nv = std::clamp(double(nDotV), 1e-4, 1.0);
  const double vx = std::sqrt(1 - nv * nv), vz = nv;  // v in the plane y = 0
  double sumA = 0, sumB = 0;
  for (int s = 0; s < samples; ++s) {
    const double u1 = (s + 0.5) / samples, u2 = radicalInverse2(uint32_t(s));
    // h with density D(h) (n.h): cos^2 theta_h = (1 - u) / (1 + (a2 - 1) u).
    const double cos2 = (1 - u1) / (1 + (a2 - 1) * u1);
    const double ch = std::sqrt(cos2), sh = std::sqrt(std::max(0.0, 1 - cos2));
    const double phi = 2 * std::numbers::pi * u2;
    const double hx = sh * std::cos(phi), hy = sh * std::sin(phi), hz = ch;
    const double vh = vx * hx + vz * hz;
    if (vh <= 0) continue;
    const double lx = 2 * vh * hx - vx, ly = 2 * vh * hy, lz = 2 * vh * hz - vz;
    if (lz <= 0) continue;
    // Smith's height-correlated visibility G / (4 n.l n.v), as brdf.glsl's smithVisibility.
    const double sin2v = vx * vx, sin2l = lx * lx + ly * ly;
    const double vis =
        0.5 / (lz * std::sqrt(vz * vz + a2 * sin2v) + vz * std::sqrt(lz * lz + a2 * sin2l));
    // f cos / pdf(l), pdf(l) = D(h) n.h / (4 v.h): D cancels.
    const double w = 4 * vis * lz * vh / hz;
    const double fc = std::pow(1 - vh, 5.0);
    sumA += (1 - fc) * w;
    sumB += fc * w;
  }
  *a = float(sumA / samples);
  *b = float(sumB / samples);
}

SplitSumTable splitSumTable(int size, int samples) {
  SplitSumTable t;
  t.size = size;
  t.ab.resize(size_t(size) * size * 2);
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) {
      const size_t k = 2 * (size_t(j) * size + i);
      splitSumEntry((i + 0.5f) / size, (j + 0.5f) / size, samples, &t.ab[k], &t.ab[k + 1]);
    }
  return t;
}

}  // namespace nestlight::gi
