// The chi-square helper itself (tests/gi/chi2.h): its incomplete gamma function against closed
// forms and published quantiles, its quadrature on a narrow lobe, and that it accepts a correct
// sampler and rejects a subtly wrong one.
#include "gi/chi2.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace nestlight::gi;
using namespace nestlight::gi::chi2;

TEST(Chi2, IncompleteGammaMatchesClosedForms) {
  for (double x : {1e-3, 0.1, 0.9, 1.0, 2.5, 5.0, 30.0, 200.0}) {
    // 1e-12 relative: both branches converge to ~1e-16; lgamma and exp cost a few ulps more.
    EXPECT_NEAR(regularizedGammaQ(1, x), std::exp(-x), 1e-12 * std::exp(-x) + 1e-300) << x;
    EXPECT_NEAR(regularizedGammaQ(0.5, x), std::erfc(std::sqrt(x)),
                1e-12 * std::erfc(std::sqrt(x)) + 1e-300)
        << x;
    double q3 = std::exp(-x) * (1 + x + x * x / 2);
    EXPECT_NEAR(regularizedGammaQ(3, x), q3, 1e-12 * q3 + 1e-300) << x;
  }
  EXPECT_EQ(regularizedGammaQ(2, 0), 1);
}

TEST(Chi2, SurvivalMatchesPublishedQuantiles) {
  // Upper 1% points of chi-square (NIST/SEMATECH e-Handbook, table 1.3.6.7.4, 3 decimals):
  // the tables' rounding is < 5e-4 in the statistic, a relative change < 1e-3 in p.
  EXPECT_NEAR(chi2Survival(23.209, 10), 0.01, 1e-5);
  EXPECT_NEAR(chi2Survival(135.807, 100), 0.01, 1e-5);
  EXPECT_NEAR(chi2Survival(6.635, 1), 0.01, 1e-5);
  // Two degrees of freedom: Q = exp(-x/2) exactly.
  EXPECT_NEAR(chi2Survival(9.0, 2), std::exp(-4.5), 1e-14);
}

TEST(Chi2, QuadratureResolvesANarrowOffAxisLobe) {
  // GGX D(h) cos(theta_h) with alpha = 0.0025 integrates to 1; tilt it off the pole to sit
  // across bin edges. The peak is ~5 mrad wide in bins of 98 mrad.
  const float alpha2 = 0.0025f * 0.0025f;
  const float c = std::cos(0.7f), s = std::sin(0.7f);
  auto f = [&](const glm::vec3& d) -> double {
    glm::vec3 h(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
    if (h.z <= 0) return 0;
    double t = double(h.x) * h.x + double(h.y) * h.y + alpha2 * double(h.z) * h.z;
    return alpha2 / (M_PI * t * t) * h.z;
  };
  // 3e-6: the quadrature keeps 1e-6 relative per bin, plus 1e-10 absolute over 2048 bins.
  EXPECT_NEAR(integrateSphere(f, M_PI, 32, 64), 1.0, 3e-6);
}

TEST(Chi2, AcceptsACorrectSamplerAndRejectsAWrongOne) {
  Chi2Options o;
  o.samples = 200000;
  o.tests = 2;
  auto cosine = [](Rng& rng) -> std::optional<glm::vec3> {
    return sampleCosineHemisphere(rng.uniform2());
  };
  Chi2Result good = chi2Test(
      cosine, [](const glm::vec3& d) { return d.z > 0 ? d.z / M_PI : 0.0; }, o);
  EXPECT_TRUE(good.passed) << good.message;
  EXPECT_NEAR(good.pdfIntegral, 1, 1e-6);
  // cos^1.1 instead of cos: densities differ by a few percent, which 200k samples resolve.
  Chi2Result bad = chi2Test(
      cosine,
      [](const glm::vec3& d) {
        return d.z > 0 ? 2.1 / (2 * M_PI) * std::pow(double(d.z), 1.1) : 0.0;
      },
      o);
  EXPECT_FALSE(bad.passed) << bad.message;
  // A sampler that rejects half of its samples while its pdf integrates to 1 fails too.
  auto lossy = [](Rng& rng) -> std::optional<glm::vec3> {
    glm::vec3 d = sampleCosineHemisphere(rng.uniform2());
    if (rng.uniform() < 0.5f) return std::nullopt;
    return d;
  };
  Chi2Result lost = chi2Test(
      lossy, [](const glm::vec3& d) { return d.z > 0 ? d.z / M_PI : 0.0; }, o);
  EXPECT_FALSE(lost.passed) << lost.message;
}
