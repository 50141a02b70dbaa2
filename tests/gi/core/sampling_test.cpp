#include "nestlight/gi/sampling.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using namespace nestlight::gi;

TEST(Sampling, FrameIsOrthonormalForEveryNormal) {
  Rng rng(7);
  for (int i = 0; i < 10000; ++i) {
    glm::vec3 n = sampleUniformSphere(rng.uniform2());
    if (i == 0) n = {0, 0, -1};  // the branchless basis's singular direction
    if (i == 1) n = {0, 0, 1};
    Frame f = Frame::fromNormal(n);
    // 1e-5: a few float ulps of error in each product of unit vectors.
    EXPECT_NEAR(glm::dot(f.s, f.t), 0, 1e-5);
    EXPECT_NEAR(glm::dot(f.s, f.n), 0, 1e-5);
    EXPECT_NEAR(glm::length(f.s), 1, 1e-5);
    EXPECT_NEAR(glm::length(f.t), 1, 1e-5);
    glm::vec3 v = f.toWorld(f.toLocal({0.3f, -0.2f, 0.9f}));
    EXPECT_NEAR(v.x, 0.3f, 1e-5);
  }
}

TEST(Sampling, Distribution1DPdfMatchesFunctionAndSkipsZeroBins) {
  std::vector<float> f = {0, 1, 3, 0, 0, 4};
  Distribution1D d(f);
  EXPECT_FLOAT_EQ(d.integral(), 8.0f / 6);
  Rng rng(3);
  std::vector<int> hits(f.size());
  const int n = 80000;
  for (int i = 0; i < n; ++i) {
    float pdf;
    int idx;
    float x = d.sampleContinuous(rng.uniform(), &pdf, &idx);
    ASSERT_GE(x, 0);
    ASSERT_LT(x, 1);
    ASSERT_GT(f[idx], 0) << "sampled a zero bin";
    EXPECT_FLOAT_EQ(pdf, d.pdf(x));
    hits[idx]++;
  }
  for (size_t i = 0; i < f.size(); ++i) {
    double expect = n * f[i] / 8.0;
    // 5 standard deviations of a binomial count: fails by chance with p < 1e-6.
    EXPECT_NEAR(hits[i], expect, 5 * std::sqrt(expect + 1)) << i;
  }
}

TEST(Sampling, AllZeroOrNonFiniteDistributionFallsBackToUniform) {
  std::vector<float> zero(4, 0.0f), bad = {NAN, INFINITY, -1, 0};
  for (auto* f : {&zero, &bad}) {
    Distribution1D d(*f);
    EXPECT_EQ(d.integral(), 0);
    float pdf;
    float x = d.sampleContinuous(0.6f, &pdf);
    EXPECT_NEAR(x, 0.6f, 1e-6);
    EXPECT_EQ(pdf, 1.0f);
  }
}

TEST(Sampling, Distribution2DPdfIntegratesToOne) {
  std::vector<float> f = {1, 2, 0, 4, 0, 0, 5, 6, 1e6f, 0, 0, 1};
  Distribution2D d(f, 4, 3);
  // Riemann sum at bin centres is exact for a piecewise-constant pdf.
  double sum = 0;
  for (int v = 0; v < 3; ++v)
    for (int u = 0; u < 4; ++u) sum += d.pdf({(u + 0.5f) / 4, (v + 0.5f) / 3}) / 12.0;
  EXPECT_NEAR(sum, 1.0, 1e-5);
  Rng rng(11);
  for (int i = 0; i < 1000; ++i) {
    float pdf;
    glm::vec2 uv = d.sampleContinuous(rng.uniform2(), &pdf);
    EXPECT_GT(pdf, 0);
    EXPECT_NEAR(pdf, d.pdf(uv), pdf * 1e-5f);
  }
}

TEST(Sampling, CosineHemisphereStaysInHemisphere) {
  Rng rng(5);
  double meanCos = 0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    glm::vec3 w = sampleCosineHemisphere(rng.uniform2());
    ASSERT_GE(w.z, 0);
    ASSERT_NEAR(glm::length(w), 1, 1e-5);
    meanCos += w.z / n;
  }
  // E[cos] under cos/pi is 2/3; the standard error is ~0.24/sqrt(n) = 7.5e-4; 5 sigma.
  EXPECT_NEAR(meanCos, 2.0 / 3.0, 4e-3);
}
