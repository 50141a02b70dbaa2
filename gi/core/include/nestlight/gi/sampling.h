// Sampling building blocks shared by the materials, the environment map and the path tracer:
// a small counter-based RNG, an orthonormal frame, warps from [0,1)^2 and piecewise-constant
// distributions (pbrt-v4, section A.5 / 2.4 "Sampling 1D and 2D functions").
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <span>
#include <vector>

namespace nestlight::gi {

using Rgb = glm::vec3;

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kInvPi = 0.31830988618379067154f;
// The largest float below 1: u in [0, kOneMinusEpsilon] keeps inverse-CDF lookups in range.
inline constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;

inline float luminance(const Rgb& c) {
  return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b;
}

// PCG32 (O'Neill 2014). Written here because it is ten lines and the path tracer needs a
// generator it can seed per pixel and sample cheaply; <random>'s engines are larger and slower.
class Rng {
 public:
  explicit Rng(uint64_t seed = 0x853c49e6748fea9bULL, uint64_t stream = 0xda3e39cb94b95bdbULL) {
    state_ = 0;
    inc_ = (stream << 1u) | 1u;
    next();
    state_ += seed;
    next();
  }
  uint32_t next() {
    uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + inc_;
    uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = uint32_t(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((-rot) & 31));
  }
  float uniform() { return std::min(kOneMinusEpsilon, float(next()) * 0x1p-32f); }
  glm::vec2 uniform2() {
    float a = uniform();
    return {a, uniform()};
  }

 private:
  uint64_t state_, inc_;
};

// Orthonormal basis around a unit normal n (Duff et al. 2017, branchless). Local frames have
// the normal as +z: BSDFs work in this frame.
struct Frame {
  glm::vec3 s, t, n;
  static Frame fromNormal(const glm::vec3& n);
  glm::vec3 toLocal(const glm::vec3& v) const {
    return {glm::dot(v, s), glm::dot(v, t), glm::dot(v, n)};
  }
  glm::vec3 toWorld(const glm::vec3& v) const { return s * v.x + t * v.y + n * v.z; }
};

glm::vec3 sampleCosineHemisphere(glm::vec2 u);  // local frame, z up; pdf = cos/pi
inline float cosineHemispherePdf(float cosTheta) {
  return cosTheta > 0 ? cosTheta * kInvPi : 0;
}
glm::vec3 sampleUniformSphere(glm::vec2 u);  // pdf = 1/(4 pi)
inline constexpr float kUniformSpherePdf = 0.25f * kInvPi;
glm::vec2 sampleUniformDisk(glm::vec2 u);      // concentric map (Shirley-Chiu), unit disk
glm::vec3 sampleUniformTriangle(glm::vec2 u);  // barycentrics (b0, b1, b2)

// Veach's power heuristic (beta = 2) for combining two strategies.
inline float powerHeuristic(float fPdf, float gPdf) {
  float f = fPdf * fPdf, g = gPdf * gPdf;
  if (f == 0) return 0;
  if (std::isinf(f)) return 1;
  return f / (f + g);
}

// Piecewise-constant 1D distribution over [0,1). All-zero or non-finite functions fall back to
// uniform so callers never divide by zero; `integral()` still reports 0 then.
class Distribution1D {
 public:
  Distribution1D() = default;
  explicit Distribution1D(std::span<const float> f);
  // Returns x in [0,1); pdf is the density with respect to x; index the bin.
  float sampleContinuous(float u, float* pdf, int* index = nullptr) const;
  int sampleDiscrete(float u, float* pmf = nullptr) const;
  float pdf(float x) const;
  float integral() const { return integral_; }
  size_t size() const { return func_.size(); }
  float func(size_t i) const { return func_[i]; }

 private:
  std::vector<float> func_, cdf_;
  float integral_ = 0;
  bool uniform_ = false;
};

// Piecewise-constant 2D distribution over [0,1)^2, rows = v, columns = u.
class Distribution2D {
 public:
  Distribution2D() = default;
  Distribution2D(std::span<const float> f, int width, int height);
  glm::vec2 sampleContinuous(glm::vec2 u, float* pdf) const;
  float pdf(glm::vec2 uv) const;
  float integral() const { return marginal_.integral(); }

 private:
  std::vector<Distribution1D> conditional_;
  Distribution1D marginal_;
};

}  // namespace nestlight::gi
