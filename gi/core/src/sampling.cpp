// Warps and piecewise-constant distributions: pbrt-v4 section A.5 and Shirley & Chiu 1997.
#include "nestlight/gi/sampling.h"

#include <algorithm>
#include <cmath>

#include "nestlight/octree/error.h"

namespace nestlight::gi {

Frame Frame::fromNormal(const glm::vec3& n) {
  float sign = std::copysign(1.0f, n.z);
  float a = -1.0f / (sign + n.z);
  float b = n.x * n.y * a;
  return {glm::vec3(1 + sign * n.x * n.x * a, sign * b, -sign * n.x),
          glm::vec3(b, sign + n.y * n.y * a, -n.y), n};
}

glm::vec2 sampleUniformDisk(glm::vec2 u) {
  glm::vec2 o = 2.0f * u - 1.0f;
  if (o.x == 0 && o.y == 0) return {0, 0};
  float r, theta;
  if (std::abs(o.x) > std::abs(o.y)) {
    r = o.x;
    theta = (kPi / 4) * (o.y / o.x);
  } else {
    r = o.y;
    theta = kPi / 2 - (kPi / 4) * (o.x / o.y);
  }
  return r * glm::vec2(std::cos(theta), std::sin(theta));
}

glm::vec3 sampleCosineHemisphere(glm::vec2 u) {
  glm::vec2 d = sampleUniformDisk(u);
  float z = std::sqrt(std::max(0.0f, 1 - d.x * d.x - d.y * d.y));
  return {d.x, d.y, z};
}

glm::vec3 sampleUniformSphere(glm::vec2 u) {
  float z = 1 - 2 * u.x;
  float r = std::sqrt(std::max(0.0f, 1 - z * z));
  float phi = 2 * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi), z};
}

glm::vec3 sampleUniformTriangle(glm::vec2 u) {
  // Heitz 2019: area-preserving, no square root.
  float b0, b1;
  if (u.x < u.y) {
    b0 = u.x / 2;
    b1 = u.y - b0;
  } else {
    b1 = u.y / 2;
    b0 = u.x - b1;
  }
  return {b0, b1, 1 - b0 - b1};
}

Distribution1D::Distribution1D(std::span<const float> f)
    : func_(f.begin(), f.end()), cdf_(f.size() + 1) {
  NL_CHECK(!f.empty());
  size_t n = func_.size();
  double sum = 0;
  cdf_[0] = 0;
  std::vector<double> acc(n + 1, 0.0);
  for (size_t i = 0; i < n; ++i) {
    float v = func_[i];
    if (!std::isfinite(v) || v < 0) v = 0;  // a NaN texel must not poison the whole table
    func_[i] = v;
    sum += double(v) / n;
    acc[i + 1] = sum;
  }
  integral_ = float(sum);
  uniform_ = !(sum > 0) || !std::isfinite(sum);
  for (size_t i = 1; i <= n; ++i) cdf_[i] = uniform_ ? float(double(i) / n) : float(acc[i] / sum);
  cdf_[n] = 1;
}

float Distribution1D::sampleContinuous(float u, float* pdf, int* index) const {
  size_t n = func_.size();
  // Last cdf entry <= u.
  auto it = std::upper_bound(cdf_.begin(), cdf_.end(), u);
  size_t i = size_t(std::clamp<ptrdiff_t>((it - cdf_.begin()) - 1, 0, ptrdiff_t(n) - 1));
  // Skip zero-width bins that upper_bound can land on when u equals a repeated cdf value.
  while (i + 1 < n && cdf_[i + 1] - cdf_[i] <= 0) ++i;
  if (index) *index = int(i);
  float width = cdf_[i + 1] - cdf_[i];
  float du = width > 0 ? (u - cdf_[i]) / width : 0.5f;
  du = std::clamp(du, 0.0f, kOneMinusEpsilon);
  if (pdf) *pdf = uniform_ ? 1.0f : func_[i] / integral_;
  return std::min((float(i) + du) / float(n), kOneMinusEpsilon);
}

int Distribution1D::sampleDiscrete(float u, float* pmf) const {
  int i;
  sampleContinuous(u, nullptr, &i);
  if (pmf) *pmf = cdf_[i + 1] - cdf_[i];
  return i;
}

float Distribution1D::pdf(float x) const {
  if (!(x >= 0 && x < 1)) return 0;
  if (uniform_) return 1.0f;
  size_t i = std::min(size_t(x * func_.size()), func_.size() - 1);
  return func_[i] / integral_;
}

Distribution2D::Distribution2D(std::span<const float> f, int width, int height) {
  NL_CHECK(width > 0 && height > 0 && f.size() == size_t(width) * height);
  conditional_.reserve(height);
  std::vector<float> marginal(height);
  for (int v = 0; v < height; ++v) {
    conditional_.emplace_back(f.subspan(size_t(v) * width, width));
    marginal[v] = conditional_.back().integral();
  }
  marginal_ = Distribution1D(marginal);
}

glm::vec2 Distribution2D::sampleContinuous(glm::vec2 u, float* pdf) const {
  float pdfs[2];
  int v;
  float d1 = marginal_.sampleContinuous(u.y, &pdfs[1], &v);
  float d0 = conditional_[v].sampleContinuous(u.x, &pdfs[0]);
  if (pdf) *pdf = pdfs[0] * pdfs[1];
  return {d0, d1};
}

float Distribution2D::pdf(glm::vec2 uv) const {
  if (!(uv.y >= 0 && uv.y < 1)) return 0;
  size_t v = std::min(size_t(uv.y * conditional_.size()), conditional_.size() - 1);
  return marginal_.pdf(uv.y) * conditional_[v].pdf(uv.x);
}

}  // namespace nestlight::gi
