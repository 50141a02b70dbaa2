// The BSDFs of gi/core/src/material.cpp: every sampler against its pdf by chi-square (pbrt-v4's
// BSDF tests), sampleBsdf against pdfBsdf/evalBsdf, reciprocity, the white furnace (directional
// albedo by Monte Carlo and by quadrature), the energy GGX loses at roughness 1, and finite,
// non-negative values at grazing angles and below the horizon.
#include "nestlight/gi/material.h"

#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "gi/chi2.h"

using namespace nestlight::gi;
using namespace nestlight::gi::chi2;

namespace {

Material lambert(Rgb base) {
  Material m;
  m.type = MaterialType::Lambert;
  m.baseColor = base;
  return m;
}

Material ggx(float roughness, float metallic, Rgb base = Rgb(0.9f, 0.6f, 0.3f)) {
  Material m;
  m.type = MaterialType::GGX;
  m.roughness = roughness;
  m.metallic = metallic;
  m.baseColor = base;
  return m;
}

struct PrincipledParams {
  float roughness = 0.5f, metallic = 0, specular = 0.5f, specularTint = 0, sheen = 0,
        sheenTint = 0.5f, clearcoat = 0, clearcoatGloss = 1;
};

Material principled(const PrincipledParams& p, Rgb base = Rgb(0.9f, 0.6f, 0.3f)) {
  Material m;
  m.type = MaterialType::Principled;
  m.baseColor = base;
  m.roughness = p.roughness;
  m.metallic = p.metallic;
  m.specular = p.specular;
  m.specularTint = p.specularTint;
  m.sheen = p.sheen;
  m.sheenTint = p.sheenTint;
  m.clearcoat = p.clearcoat;
  m.clearcoatGloss = p.clearcoatGloss;
  return m;
}

glm::vec3 direction(float theta, float phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

struct Case {
  std::string name;
  Material m;
};

// The sampler cases: every type, roughness at both ends (0.05 is the sharpest lobe the chi-square
// bins still resolve; 1 the widest), metals and dielectrics, the principled lobes one by one.
std::vector<Case> samplerCases() {
  return {
      {"lambert", lambert(Rgb(0.8f, 0.5f, 0.2f))},
      {"ggx r0.05 m0", ggx(0.05f, 0)},
      {"ggx r0.05 m1", ggx(0.05f, 1)},
      {"ggx r0.3 m0.5", ggx(0.3f, 0.5f)},
      {"ggx r1 m0", ggx(1, 0)},
      {"ggx r1 m1", ggx(1, 1)},
      {"principled r0.05 sheen clearcoat",
       principled({.roughness = 0.05f, .sheen = 1, .clearcoat = 1})},
      {"principled r0.5 sheen tint clearcoat gloss 0.5", principled({.roughness = 0.5f,
                                                                     .specularTint = 1,
                                                                     .sheen = 1,
                                                                     .sheenTint = 1,
                                                                     .clearcoat = 1,
                                                                     .clearcoatGloss = 0.5f})},
      {"principled r1 clearcoat gloss 0",
       principled({.roughness = 1, .sheen = 0.5f, .clearcoat = 1, .clearcoatGloss = 0})},
      {"principled r0.3 m1 clearcoat",
       principled({.roughness = 0.3f, .metallic = 1, .clearcoat = 0.5f})},
  };
}

// Viewing angles: head-on, oblique and near grazing, off the phi = 0 plane so that no symmetry of
// the bins hides an error in phi.
const float kThetas[] = {0.0f, 1.0f, 1.45f};
constexpr float kPhiO = 0.3f;

// Samples per chi-square test. Under AddressSanitizer (about 8 times slower here) the Release run
// is the statistical test and this run checks memory and undefined behaviour on the same paths,
// so it draws a fifth: still over 40 expected samples in the average bin, and every bound below
// is written in terms of the sample count.
#ifdef __SANITIZE_ADDRESS__
constexpr size_t kChi2Samples = 200000;
constexpr int kFurnaceSamples = 20000;
#else
constexpr size_t kChi2Samples = 1000000;
constexpr int kFurnaceSamples = 100000;
#endif

std::string describe(const Case& c, float theta) {
  return c.name + " theta_o " + std::to_string(theta);
}

}  // namespace

TEST(Material, TypeNames) {
  EXPECT_STREQ(materialTypeName(MaterialType::Lambert), "lambert");
  EXPECT_STREQ(materialTypeName(MaterialType::GGX), "ggx");
  EXPECT_STREQ(materialTypeName(MaterialType::Principled), "principled");
}

// One test per case and viewing angle, so that ctest spreads the 30 chi-square runs over cores.
class MaterialChi2 : public testing::TestWithParam<int> {};

TEST_P(MaterialChi2, SamplerMatchesItsPdf) {
  const auto cases = samplerCases();
  const int index = GetParam();
  const Case& c = cases[size_t(index) / std::size(kThetas)];
  const float theta = kThetas[size_t(index) % std::size(kThetas)];
  Chi2Options o;
  o.samples = kChi2Samples;
  // The whole family still shares one significance (Sidak), as if run in one test.
  o.tests = int(cases.size() * std::size(kThetas));
  o.seed = uint64_t(index) + 1;
  const glm::vec3 wo = direction(theta, kPhiO);
  size_t pdfMismatch = 0, fMismatch = 0;
  auto sampler = [&](Rng& rng) -> std::optional<glm::vec3> {
    glm::vec2 u = rng.uniform2();
    float uLobe = rng.uniform();
    auto s = sampleBsdf(c.m, wo, u, uLobe);
    if (!s) return std::nullopt;
    // The returned pdf and f must be what pdfBsdf and evalBsdf say for the returned
    // direction: MIS weighs light samples with pdfBsdf. 1e-5 relative: the same
    // arithmetic in a different order would differ by a few float ulps, nothing more.
    float pdf = pdfBsdf(c.m, wo, s->wi);
    if (!(std::abs(s->pdf - pdf) <= 1e-5f * pdf)) ++pdfMismatch;
    Rgb f = evalBsdf(c.m, wo, s->wi);
    for (int k = 0; k < 3; ++k)
      if (!(std::abs(s->f[k] - f[k]) <= 1e-5f * f[k] + 1e-30f)) ++fMismatch;
    return s->wi;
  };
  Chi2Result r = chi2Test(
      sampler, [&](const glm::vec3& wi) { return double(pdfBsdf(c.m, wo, wi)); }, o);
  EXPECT_TRUE(r.passed) << describe(c, theta) << ": " << r.message;
  std::printf("%-50s %s\n", describe(c, theta).c_str(),
              r.message.substr(0, r.message.find(';')).c_str());
  EXPECT_EQ(pdfMismatch, 0u) << describe(c, theta);
  EXPECT_EQ(fMismatch, 0u) << describe(c, theta);
  // The pdf integrates to the share of samples that were not rejected. Bound: 5 binomial
  // standard deviations of the rejected fraction plus the quadrature's 1e-6 relative per bin
  // (summed, at most 1e-6) and its absolute 1e-10 per bin (2e-7 over 2048 bins).
  double accepted = 1 - double(r.failedSamples) / double(o.samples);
  double sigma = std::sqrt(accepted * (1 - accepted) / double(o.samples));
  EXPECT_NEAR(r.pdfIntegral, accepted, 5 * sigma + 2e-6) << describe(c, theta);
}

INSTANTIATE_TEST_SUITE_P(Material, MaterialChi2,
                         testing::Range(0, int(samplerCases().size() * std::size(kThetas))),
                         [](const testing::TestParamInfo<int>& info) {
                           // "ggx r0.05 m1" at the second angle: ggx_r0_05_m1_theta1
                           std::string name =
                               samplerCases()[size_t(info.param) / std::size(kThetas)].name;
                           for (char& ch : name)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return name + "_theta" +
                                  std::to_string(size_t(info.param) % std::size(kThetas));
                         });

TEST(Material, BsdfsAreReciprocal) {
  auto cases = samplerCases();
  cases.push_back({"principled r0 everything", principled({.roughness = 0,
                                                           .metallic = 0.3f,
                                                           .specular = 1,
                                                           .specularTint = 0.5f,
                                                           .sheen = 1,
                                                           .sheenTint = 1,
                                                           .clearcoat = 1,
                                                           .clearcoatGloss = 0.2f})});
  Rng rng(17);
  for (const Case& c : cases)
    for (int i = 0; i < 2000; ++i) {
      glm::vec3 a = sampleUniformSphere(rng.uniform2()), b = sampleUniformSphere(rng.uniform2());
      a.z = std::abs(a.z), b.z = std::abs(b.z);
      Rgb fab = evalBsdf(c.m, a, b), fba = evalBsdf(c.m, b, a);
      for (int k = 0; k < 3; ++k)
        // 1e-5 relative: f(a,b) and f(b,a) multiply the same factors in another order.
        ASSERT_NEAR(fab[k], fba[k], 1e-5f * std::max(fab[k], fba[k]) + 1e-30f)
            << c.name << " channel " << k;
    }
}

TEST(Material, LambertAlbedoIsTheBaseColourExactly) {
  const Rgb base(0.8f, 0.5f, 0.2f);
  for (float theta : {0.0f, 0.7f, 1.5f, 1.5707f}) {
    Rgb a = directionalAlbedo(lambert(base), direction(theta, 0.2f), 20000, 3);
    // Cosine sampling makes every sample's weight f cos / pdf = base exactly; the only error is
    // float rounding of each weight (~1e-7 relative), summed in double.
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], base[k], 1e-6f) << theta;
  }
}

namespace {

struct McAlbedo {
  double mean = 0, stderror = 0;
};

// The largest channel's directional albedo and the standard error of its estimate.
McAlbedo mcAlbedo(const Material& m, const glm::vec3& wo, int n, uint64_t seed) {
  Rng rng(seed);
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    glm::vec2 u = rng.uniform2();
    float uLobe = rng.uniform();
    double w = 0;
    if (auto s = sampleBsdf(m, wo, u, uLobe)) {
      Rgb v = s->f * (s->wi.z / s->pdf);
      w = std::max({v.r, v.g, v.b});
    }
    sum += w;
    sum2 += w * w;
  }
  McAlbedo r;
  r.mean = sum / n;
  r.stderror = std::sqrt(std::max(0.0, sum2 / n - r.mean * r.mean) / (n - 1));
  return r;
}

// The same albedo by quadrature of max-channel f cos over the hemisphere: independent of the
// samplers and their pdfs.
double quadratureAlbedo(const Material& m, const glm::vec3& wo) {
  auto f = [&](const glm::vec3& wi) -> double {
    Rgb v = evalBsdf(m, wo, wi);
    return double(std::max({v.r, v.g, v.b})) * std::max(0.0f, wi.z);
  };
  return integrateSphere(f, M_PI / 2, 16, 32);
}

std::vector<Case> whiteCases() {
  const Rgb white(1.0f);
  std::vector<Case> cases = {{"lambert", lambert(white)}};
  for (float r : {0.05f, 0.5f, 1.0f})
    for (float metallic : {0.0f, 1.0f}) {
      char name[64];
      std::snprintf(name, sizeof name, "ggx r%g m%g", r, metallic);
      cases.push_back({name, ggx(r, metallic, white)});
    }
  for (float r : {0.05f, 0.5f, 1.0f}) {
    char name[64];
    std::snprintf(name, sizeof name, "principled r%g", r);
    cases.push_back({std::string(name) + " plain", principled({.roughness = r}, white)});
    cases.push_back(
        {std::string(name) + " specular 1 sheen 1 clearcoat 1 gloss 0",
         principled(
             {.roughness = r, .specular = 1, .sheen = 1, .clearcoat = 1, .clearcoatGloss = 0},
             white)});
    cases.push_back(
        {std::string(name) + " sheen 1 clearcoat 1 gloss 1",
         principled({.roughness = r, .sheen = 1, .clearcoat = 1, .clearcoatGloss = 1}, white)});
    cases.push_back({std::string(name) + " metallic 1 clearcoat 1",
                     principled({.roughness = r, .metallic = 1, .clearcoat = 1}, white)});
  }
  return cases;
}

}  // namespace

TEST(Material, WhiteFurnaceAlbedoAtMostOne) {
  const float cosines[] = {1.0f, 0.7f, 0.4f, 0.15f, 0.03f, 1e-3f};
  const int n = kFurnaceSamples;
  for (const Case& c : whiteCases()) {
    double worst = 0, worstMu = 0;
    for (float mu : cosines) {
      glm::vec3 wo(std::sqrt(1 - mu * mu), 0, mu);
      McAlbedo mc = mcAlbedo(c.m, wo, n, 5);
      if (mc.mean > worst) worst = mc.mean, worstMu = mu;
      // Monte Carlo may exceed 1 by its own noise only: 5 standard errors (p < 3e-7 each).
      EXPECT_LE(mc.mean, 1 + 5 * mc.stderror + 1e-6) << c.name << " mu " << mu;
      // directionalAlbedo is the same estimator with its own seed: it agrees within 5 standard
      // errors of either estimate (their difference has sqrt(2) of one; 5 covers it).
      // 10 / n more: near-mirror lobes reject ~1e-5 of their samples (a reflection below the
      // horizon), a rare event the standard error does not see; 10 / n is ten such.
      const double rare = 10.0 / n;
      Rgb a = directionalAlbedo(c.m, wo, n, 99);
      EXPECT_NEAR(std::max({a.r, a.g, a.b}), mc.mean, 5 * std::sqrt(2.0) * mc.stderror + rare)
          << c.name << " mu " << mu;
      if (mu == 1.0f || mu == 0.4f || mu == 0.03f) {
        // The quadrature holds 1e-6 relative per patch; no noise, so the bound is tight.
        double q = quadratureAlbedo(c.m, wo);
        EXPECT_LE(q, 1 + 1e-5) << c.name << " mu " << mu;
        EXPECT_NEAR(q, mc.mean, 5 * mc.stderror + rare) << c.name << " mu " << mu;
      }
    }
    std::printf("white furnace %-50s max albedo %.4f at mu %g\n", c.name.c_str(), worst, worstMu);
  }
}

TEST(Material, GgxEnergyLossAtRoughnessOne) {
  // A white metal (F = 1) at roughness 1 (alpha = 1): what single-scattering GGX loses to
  // masking and shadowing (the energy multiple scattering would return; Kulla & Conty 2017).
  // At alpha = 1, D = 1/pi and the height-correlated G2 / (4 cos_o cos_i) = 1 / (2 (mu + cos_i)),
  // so E(mu) = integral_0^1 c / (mu + c) dc = 1 - mu ln(1 + 1/mu): 1 - ln 2 = 0.307 head-on
  // (69.3% lost), 0.451 at mu = 0.5, 0.760 at mu = 0.1. Monte Carlo and quadrature must both
  // find it: the closed form is independent of the code.
  const Material m = ggx(1, 1, Rgb(1.0f));
  double lossAverage = 0;  // 2 integral (1 - E(mu)) mu dmu, midpoint rule on the closed form
  for (int i = 0; i < 10000; ++i) {
    double mu = (i + 0.5) / 10000;
    lossAverage += 2 * mu * mu * std::log(1 + 1 / mu) / 10000;
  }
  std::printf("GGX roughness 1: cosine-weighted average loss %.1f%%\n", 100 * lossAverage);
  for (float mu : {1.0f, 0.5f, 0.1f, 0.01f}) {
    glm::vec3 wo(std::sqrt(1 - mu * mu), 0, mu);
    double exact = 1 - double(mu) * std::log(1 + 1 / double(mu));
    McAlbedo mc = mcAlbedo(m, wo, 400000, 7);
    double q = quadratureAlbedo(m, wo);
    std::printf(
        "GGX roughness 1, mu %.2f: albedo exact %.4f, MC %.4f +- %.4f, quadrature %.4f, loss "
        "%.1f%%\n",
        mu, exact, mc.mean, mc.stderror, q, 100 * (1 - exact));
    EXPECT_NEAR(mc.mean, exact, 5 * mc.stderror) << mu;
    EXPECT_NEAR(q, exact, 1e-5) << mu;  // the quadrature's 1e-6 relative per patch, with margin
  }
}

TEST(Material, GrazingAndBelowHorizonAreFiniteAndNonNegative) {
  std::vector<Material> materials;
  for (float r : {0.0f, 1e-3f, 0.05f, 1.0f})
    for (float metallic : {0.0f, 1.0f}) {
      materials.push_back(ggx(r, metallic));
      materials.push_back(principled({.roughness = r,
                                      .metallic = metallic,
                                      .specularTint = 1,
                                      .sheen = 1,
                                      .clearcoat = 1,
                                      .clearcoatGloss = r}));
    }
  materials.push_back(lambert(Rgb(0.5f)));
  materials.push_back(principled({}, Rgb(0.0f)));  // black: the tint has no hue to take
  materials.push_back(ggx(0.5f, 1, Rgb(0.0f)));    // black metal: F0 = 0 head-on

  const float zs[] = {1.0f, 0.5f, 1e-3f, 1e-7f, 1e-9f, 1e-12f, 0.0f, -0.0f, -1e-7f, -0.5f, -1.0f};
  const float phis[] = {0.0f, 1.3f, 3.14159f};
  auto dir = [](float z, float phi) {
    float s = std::sqrt(std::max(0.0f, 1 - z * z));
    return glm::vec3(s * std::cos(phi), s * std::sin(phi), z);
  };
  auto finite = [](const Rgb& c) {
    return std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b) && c.r >= 0 && c.g >= 0 &&
           c.b >= 0;
  };
  for (const Material& m : materials) {
    for (float zo : zs)
      for (float zi : zs)
        for (float po : phis)
          for (float pi : phis) {
            glm::vec3 wo = dir(zo, po), wi = dir(zi, pi);
            Rgb f = evalBsdf(m, wo, wi);
            float pdf = pdfBsdf(m, wo, wi);
            ASSERT_TRUE(finite(f))
                << materialTypeName(m.type) << " r " << m.roughness << " zo " << zo << " zi " << zi;
            ASSERT_TRUE(std::isfinite(pdf) && pdf >= 0)
                << materialTypeName(m.type) << " zo " << zo << " zi " << zi;
            if (!(zo > 0) || !(zi > 0)) {
              EXPECT_EQ(f, Rgb(0.0f));
              EXPECT_EQ(pdf, 0.0f);
            }
            // What reaches the path tracer is f cos / pdf, bounded by the albedo's worst case.
            if (pdf > 0) {
              ASSERT_TRUE(finite(f * (wi.z / pdf)));
            }
          }
    Rng rng(23);
    for (float zo : zs) {
      glm::vec3 wo = dir(zo, 0.4f);
      for (int i = 0; i < 2000; ++i) {
        glm::vec2 u = rng.uniform2();
        if (i == 0) u = {0, 0};
        if (i == 1) u = {kOneMinusEpsilon, kOneMinusEpsilon};
        auto s = sampleBsdf(m, wo, u, rng.uniform());
        if (!(zo > 0)) {
          EXPECT_FALSE(s.has_value());
          continue;
        }
        if (!s) continue;
        ASSERT_TRUE(finite(s->f) && std::isfinite(s->pdf) && s->pdf > 0)
            << materialTypeName(m.type) << " zo " << zo;
        ASSERT_GT(s->wi.z, 0);
        // Reflection about a normalised half vector keeps |wi| = 1 to a few float ulps; 1e-4
        // only catches a direction that was never normalised.
        ASSERT_NEAR(glm::length(s->wi), 1, 1e-4);
        ASSERT_TRUE(finite(s->f * (s->wi.z / s->pdf)));
      }
    }
  }
  // NaN in, zero out.
  const glm::vec3 nan(NAN);
  EXPECT_EQ(evalBsdf(ggx(0.5f, 0), nan, glm::vec3(0, 0, 1)), Rgb(0.0f));
  EXPECT_EQ(pdfBsdf(principled({}), glm::vec3(0, 0, 1), nan), 0.0f);
  EXPECT_FALSE(sampleBsdf(ggx(0.5f, 0), nan, {0.5f, 0.5f}, 0.5f).has_value());
}
