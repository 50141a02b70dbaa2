// The exposure search of HDR expansion: Wasserstein distances between luminance histograms, and
// the search recovering a known exposure (eq. 1 and 2 of Sabbadin et al. 2019).
#include "nestlight/gi/hdr/exposure.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

namespace nestlight::gi::hdr {
namespace {

TEST(Exposure, WassersteinIsTheAreaBetweenCumulativeHistograms) {
  Histogram a = luminanceHistogram({0.1f, 0.1f}), b = luminanceHistogram({0.1f, 0.1f});
  EXPECT_DOUBLE_EQ(wasserstein(a, b), 0.0);
  // All mass in bin 12 against all in bin 76: 64 bins apart, half the range.
  a = luminanceHistogram({12.5f / kHistogramBins});
  b = luminanceHistogram({76.5f / kHistogramBins});
  EXPECT_DOUBLE_EQ(wasserstein(a, b), 64.0 / kHistogramBins);
  EXPECT_DOUBLE_EQ(wasserstein(a, b), wasserstein(b, a));
  // Out-of-range values land in the end bins; non-finite ones are counted apart, never binned.
  const Histogram c = luminanceHistogram({-1.0f, 2.0f, NAN, INFINITY});
  EXPECT_EQ(c.counted, 2u);
  EXPECT_EQ(c.skipped, 2u);
  EXPECT_DOUBLE_EQ(c.mass.front(), 0.5);
  EXPECT_DOUBLE_EQ(c.mass.back(), 0.5);
  EXPECT_DOUBLE_EQ(wasserstein(Histogram{}, a), 1.0);
}

// A photograph of 200,000 log-uniform luminances over 5 decades (1e-3 to 1e2: the dynamic
// range of 1e5), a few NaNs among them; the scan's LDR colour is the same scene exposed by e and
// clamped (eq. 2). The search finds log2 e to 0.05 stops: one bin of 128 over [0, 1] is what a
// shift of about 0.02 stops moves a mid-grey value by, and the sampled range narrows far below
// that in 10 iterations.
TEST(Exposure, SearchRecoversAKnownExposure) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-3.0, 2.0);
  std::vector<float> photo(200000);
  for (float& v : photo) v = float(std::pow(10.0, u(rng)));
  photo[17] = NAN;
  for (double log2e : {-3.3, 0.0, 4.7}) {
    std::vector<float> scan;
    for (size_t i = 0; i < photo.size(); i += 3)  // the scan sees part of the same scene
      if (std::isfinite(photo[i]))
        scan.push_back(float(std::min(1.0, std::exp2(log2e) * photo[i])));
    const ExposureSearch s = findBestExposure(photo, luminanceHistogram(scan));
    ASSERT_TRUE(s.usable);
    EXPECT_NEAR(s.log2Exposure, log2e, 0.05)
        << "distance " << s.distance << " after " << s.iterations;
    std::printf("log2 e %.2f: found %.4f (distance %.2e, %d iterations)\n", log2e, s.log2Exposure,
                s.distance, s.iterations);
    EXPECT_LT(s.distance, 0.01);
    // The first range is the photograph's: from bringing 1e2 to 1 to bringing 1e-3 to 1.
    EXPECT_NEAR(s.log2Lo, -std::log2(100.0), 0.01);
    EXPECT_NEAR(s.log2Hi, std::log2(1000.0), 0.01);
  }
}

// Hard cases: a black photograph has no exposure to find; an empty scan histogram nothing to
// match; a photograph of one luminance still gets a range (one stop either side).
TEST(Exposure, BlackPhotographsAndEmptyScansAreReportedUnusable) {
  const Histogram scan = luminanceHistogram({0.2f, 0.4f});
  EXPECT_FALSE(findBestExposure(std::vector<float>(100, 0.0f), scan).usable);
  EXPECT_FALSE(findBestExposure({NAN, INFINITY}, scan).usable);
  EXPECT_FALSE(findBestExposure({0.5f, 1.0f}, Histogram{}).usable);
  const ExposureSearch one =
      findBestExposure(std::vector<float>(100, 4.0f), luminanceHistogram({0.5f}));
  ASSERT_TRUE(one.usable);
  EXPECT_NEAR(one.log2Exposure, -3.0, 0.05);  // 4 x 2^-3 = 0.5
}

}  // namespace
}  // namespace nestlight::gi::hdr
