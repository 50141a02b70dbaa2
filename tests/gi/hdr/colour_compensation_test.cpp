// Colour compensation between a photograph and a rendering of the scan (Rohmer, Jendersie and
// Grosch, "Natural Environment Illumination: Coherent Interactive Augmented Reality for Mobile and
// non-Mobile Devices", IEEE TVCG 2017, section 4): a known camera transform is recovered, pairs are
// rejected for the paper's reasons and counted, and too few pairs fall back to the per-channel
// scale.
#include "nestlight/gi/hdr/colour_compensation.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <random>

#include "nestlight/octree/error.h"

namespace nestlight::gi::hdr {
namespace {

constexpr int kWidth = 320, kHeight = 240;
constexpr double kCameraGamma = 2.2;

// Exposure (x1.3), a warm white balance and a little channel cross-talk: what a camera's automatic
// settings do between the scan and a later photograph. Maps camera linear RGB to reference.
Eigen::Matrix3d trueTransform() {
  Eigen::Matrix3d crossTalk;
  crossTalk << 1.00, 0.06, 0.02,  //
      0.04, 1.00, 0.05,           //
      0.01, 0.07, 1.00;
  return 1.3 * Eigen::Vector3d(1.15, 1.0, 0.85).asDiagonal() * crossTalk;
}

// Smooth, moderately saturated reference colours: each channel in [0.25, 0.65] (display), with
// independent spatial frequencies so that the pairs span all of colour space (U W^2 U^T well
// conditioned). The largest step between neighbours is about 0.2 * 2 pi * 1.3 / 320 = 0.005, far
// below the gradient threshold.
Eigen::Vector3d referenceDisplay(int x, int y) {
  const double fx = x / double(kWidth), fy = y / double(kHeight), tau = 2 * std::numbers::pi;
  return {0.45 + 0.2 * std::sin(tau * (1.3 * fx + 0.4 * fy)),
          0.45 + 0.2 * std::sin(tau * (0.5 * fx - 1.1 * fy) + 1.0),
          0.45 + 0.2 * std::sin(tau * (0.9 * fx + 0.8 * fy) + 2.0)};
}

Eigen::Vector3d decode(const Eigen::Vector3d& d) {
  return d.unaryExpr([](double v) { return std::pow(v, kCameraGamma); });
}
Eigen::Vector3d encode(const Eigen::Vector3d& l) {
  return l.unaryExpr([](double v) { return std::pow(v, 1 / kCameraGamma); });
}

void setPixel(HdrImage& image, int x, int y, const Eigen::Vector3d& c) {
  image.set(x, y, Rgb(float(c.x()), float(c.y()), float(c.z())));
}
Eigen::Vector3d pixel(const HdrImage& image, int x, int y) {
  const Rgb c = image.get(x, y);
  return {c.r, c.g, c.b};
}

struct PhotoPair {
  HdrImage camera, rendering;  // display-encoded
  std::vector<uint8_t> coverage;
};

// The photograph is the rendering taken back through the inverse of `transform`: c(u) = r exactly,
// up to float storage.
PhotoPair makePhotoPair(const Eigen::Matrix3d& transform, int width = kWidth,
                        int height = kHeight) {
  PhotoPair s{HdrImage(width, height), HdrImage(width, height),
              std::vector<uint8_t>(size_t(width) * height, 1)};
  const Eigen::Matrix3d inverse = transform.inverse();
  for (int y = 0; y < height; y++) {
    for (int x = 0; x < width; x++) {
      const Eigen::Vector3d r = referenceDisplay(x, y);
      setPixel(s.rendering, x, y, r);
      setPixel(s.camera, x, y, encode(inverse * decode(r)));
    }
  }
  return s;
}

double maxError(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return (a - b).cwiseAbs().maxCoeff();
}

TEST(ColourCompensation, HueSaturationDistanceIsTakenInTheDisc) {
  // Hue wraps around: red slightly towards magenta and red slightly towards yellow are close.
  EXPECT_LT(hsDistance({0.8, 0.2, 0.25}, {0.8, 0.25, 0.2}), 0.15);
  // Near-greys of different tints are close although their hues are half a circle apart.
  EXPECT_LT(hsDistance({0.50, 0.49, 0.49}, {0.49, 0.50, 0.50}), 0.05);
  // Opposite fully saturated hues are a diameter apart; brightness does not count.
  EXPECT_NEAR(hsDistance({1, 0, 0}, {0, 1, 1}), 2.0, 1e-12);
  EXPECT_NEAR(hsDistance({0.6, 0.3, 0.2}, {0.3, 0.15, 0.1}), 0.0, 1e-12);
  // In the cylinder, brightness does count.
  EXPECT_NEAR(hsvDistance({0.6, 0.3, 0.2}, {0.3, 0.15, 0.1}), 0.3, 1e-12);
  EXPECT_DOUBLE_EQ(hsDistance({0, 0, 0}, {0.5, 0.5, 0.5}), 0.0);
}

// Test 1. The clean scene: every pixel is a valid pair. With the paper's gamma = 0.05 the fit is
// pulled towards A by gamma (A - C_true)(U W^2 U^T + gamma I)^-1; with 76,800 pairs the smallest
// eigenvalue of U W^2 U^T is in the hundreds (printed), so the pull is below 1e-4 per element.
// 1e-3 leaves room for that and still fails for any real error (a cross-talk term of C_true is
// 0.02 * 1.3 * 0.85 = 0.022). Without regularisation the fit is exact up to the float storage of
// the images (relative 6e-8, times 2.2 through the gamma curve): 1e-5.
TEST(ColourCompensation, RecoversAKnownTransform) {
  const Eigen::Matrix3d truth = trueTransform();
  const PhotoPair s = makePhotoPair(truth);

  const PairSelection selection = selectColourPairs(s.camera, s.rendering, s.coverage);
  ASSERT_EQ(selection.statistics.accepted, uint64_t(kWidth) * kHeight);
  Eigen::Matrix3d uu = Eigen::Matrix3d::Zero();
  double largestHs = 0;
  for (const ColourPair& p : selection.pairs) {
    uu += std::pow(1 - std::min(1.0, p.hsDistance), 8) * p.camera * p.camera.transpose();
    largestHs = std::max(largestHs, p.hsDistance);
  }
  const double lambdaMin = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(uu).eigenvalues()(0);
  std::printf("smallest eigenvalue of U W^2 U^T: %.1f; largest hs distance of a pair: %.3f\n",
              lambdaMin, largestHs);

  const ColourCompensation c = fitColourCompensation(selection.pairs, {}, selection.statistics);
  ASSERT_TRUE(c.usable);
  ASSERT_FALSE(c.approximated);
  const double error = maxError(c.matrix, truth);
  std::printf("gamma = 0.05: largest error per element %.3g (condition number %.3f)\n", error,
              c.conditionNumber);
  EXPECT_LT(error, 1e-3);
  // The exact pull for exact pairs is gamma (A - C_true)(U W^2 U^T + gamma I)^-1: bounded by
  // gamma |A - C_true|_2 / (lambda_min + gamma), plus the float noise of the gamma = 0 fit.
  const double pull =
      0.05 * Eigen::JacobiSVD<Eigen::Matrix3d>(c.approximation - truth).singularValues()(0) /
      (lambdaMin + 0.05);
  std::printf("bound on the pull towards A: %.3g\n", pull);
  EXPECT_LT(error, pull + 1e-6);
  EXPECT_LT(maxError(c.inverse, truth.inverse()), 1e-3);
  EXPECT_LT(maxError(c.matrix * c.inverse, Eigen::Matrix3d::Identity()), 1e-12);

  ColourCompensationOptions exact;
  exact.regularisation = 0;
  const ColourCompensation e = estimateColourCompensation(s.camera, s.rendering, s.coverage, exact);
  ASSERT_FALSE(e.approximated);
  const double exactError = maxError(e.matrix, truth);
  std::printf("gamma = 0:    largest error per element %.3g\n", exactError);
  EXPECT_LT(exactError, 1e-5);
  // The approximation is a diagonal matrix that roughly matches the channel averages; it cannot
  // express the cross-talk, so it is worse than C.
  EXPECT_GT(maxError(c.approximation, truth), 10 * error);
}

// Linear inputs give the same fit: the thresholds are in display values either way.
TEST(ColourCompensation, LinearInputsGiveTheSameFit) {
  const PhotoPair s = makePhotoPair(trueTransform());
  const ColourCompensation display = estimateColourCompensation(s.camera, s.rendering, s.coverage);
  ColourCompensationOptions options;
  options.inputsLinear = true;
  const ColourCompensation linear = estimateColourCompensation(
      linearFromDisplay(s.camera), linearFromDisplay(s.rendering), s.coverage, options);
  EXPECT_EQ(linear.statistics.accepted, display.statistics.accepted);
  EXPECT_LT(maxError(linear.matrix, display.matrix), 1e-5);
}

// Test 2. Values up to 4 (HDR) through C and back: float storage of the intermediate image costs
// about 4 * 1.3 * 6e-8 per step, amplified by the condition number (about 1.5); 1e-5 is a bound
// an order above that which a wrong inverse misses by far.
TEST(ColourCompensation, InverseRoundTrip) {
  const PhotoPair s = makePhotoPair(trueTransform());
  const ColourCompensation c = estimateColourCompensation(s.camera, s.rendering, s.coverage);
  HdrImage image(64, 48);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 4.0f);
  for (float& v : image.rgb) v = u(rng);
  const HdrImage reference = toReferenceSpace(image, c);
  const HdrImage back = toCameraSpace(reference, c);
  double largest = 0, largestMoved = 0;
  for (size_t i = 0; i < image.rgb.size(); i++) {
    largest = std::max(largest, double(std::abs(back.rgb[i] - image.rgb[i])));
    largestMoved = std::max(largestMoved, double(std::abs(reference.rgb[i] - image.rgb[i])));
  }
  EXPECT_LT(largest, 1e-5);
  EXPECT_GT(largestMoved, 0.5);  // the transform did something; values above 1 are kept
  const HdrImage encoded = displayFromLinear(image);
  const HdrImage decoded = linearFromDisplay(encoded);
  for (size_t i = 0; i < image.rgb.size(); i++) ASSERT_NEAR(decoded.rgb[i], image.rgb[i], 1e-5);
}

// Test 3. Each reason for rejection in a region of its own, far from the others, so that the
// counts are exact:
// - saturated: a 20x20 block of white in the photograph: 400 pixels; the 80 pixels that touch it
//   along a row or column see the step in their central differences (gradient);
// - no data: a 40x40 region without points: 1600 pixels; neighbours without data do not create
//   gradients;
// - edge in both images: from column 280 on, both are brighter by 0.3 (display): columns 279 and
//   280 see a central difference of 0.15 in every row: 480 pixels;
// - edge in the rendering only: a dark stripe of 2 rows (200, 201) over columns [120, 200): rows
//   199 to 202 over those columns, plus the two pixels beside each end of the stripe: 324 pixels;
// - occluder: a saturated magenta object (10% of the image, 96x80) in the photograph only. Its
//   saturation (0.97) is farther than 0.3 from any reference colour (at most 0.6 saturated) in the
//   disc: its inner 94x78 pixels go to the hue-saturation filter (7332), its one-pixel inner border
//   (348) and the pixels touching it outside (352) to gradient.
TEST(ColourCompensation, RejectsAndCountsBadPairs) {
  const Eigen::Matrix3d truth = trueTransform();
  PhotoPair s = makePhotoPair(truth);
  const Eigen::Matrix3d inverse = truth.inverse();
  for (int y = 20; y < 40; y++) {
    for (int x = 20; x < 40; x++) setPixel(s.camera, x, y, {1, 1, 1});
  }
  for (int y = 20; y < 60; y++) {
    for (int x = 60; x < 100; x++) {
      s.coverage[size_t(y) * kWidth + x] = 0;
      setPixel(s.rendering, x, y, {0, 0, 0});
    }
  }
  for (int y = 0; y < kHeight; y++) {
    for (int x = 280; x < kWidth; x++) {
      const Eigen::Vector3d r = referenceDisplay(x, y).array() + 0.3;
      setPixel(s.rendering, x, y, r);
      setPixel(s.camera, x, y, encode(inverse * decode(r)));
    }
  }
  for (int y = 200; y < 202; y++) {
    for (int x = 120; x < 200; x++) setPixel(s.rendering, x, y, 0.3 * referenceDisplay(x, y));
  }
  for (int y = 80; y < 160; y++) {
    for (int x = 140; x < 236; x++) setPixel(s.camera, x, y, {0.9, 0.03, 0.9});
  }

  const PairSelection selection = selectColourPairs(s.camera, s.rendering, s.coverage);
  const PairStatistics& st = selection.statistics;
  EXPECT_EQ(st.pixels, uint64_t(kWidth) * kHeight);
  EXPECT_EQ(st.saturated, 400u);
  EXPECT_EQ(st.noData, 1600u);
  EXPECT_EQ(st.gradient, 80u + 480u + 324u + 348u + 352u);
  EXPECT_EQ(st.hsDistance, 94u * 78u);
  EXPECT_EQ(st.hsvDistance, 0u);
  EXPECT_EQ(st.nonFinite, 0u);
  EXPECT_EQ(st.accepted + st.saturated + st.noData + st.gradient + st.hsDistance, st.pixels);
  EXPECT_EQ(selection.pairs.size(), st.accepted);

  auto classAt = [&](int x, int y) { return selection.classes[size_t(y) * kWidth + x]; };
  EXPECT_EQ(classAt(30, 30), PairClass::kSaturated);
  EXPECT_EQ(classAt(19, 30), PairClass::kGradient);
  EXPECT_EQ(classAt(80, 40), PairClass::kNoData);
  EXPECT_EQ(classAt(100, 40), PairClass::kAccepted);  // beside the hole
  EXPECT_EQ(classAt(279, 10), PairClass::kGradient);
  EXPECT_EQ(classAt(281, 10), PairClass::kAccepted);
  EXPECT_EQ(classAt(150, 199), PairClass::kGradient);
  EXPECT_EQ(classAt(150, 203), PairClass::kAccepted);
  EXPECT_EQ(classAt(180, 120), PairClass::kHsDistance);
  EXPECT_EQ(classAt(140, 120), PairClass::kGradient);

  // Every accepted pair is a true one, so the fit is as good as on the clean scene (test 1).
  const ColourCompensation c = fitColourCompensation(selection.pairs, {}, st);
  ASSERT_FALSE(c.approximated);
  const double error = maxError(c.matrix, truth);
  std::printf("with rejections and 10%% occluder: largest error per element %.3g\n", error);
  EXPECT_LT(error, 1e-3);
  EXPECT_EQ(c.statistics.accepted, st.accepted);

  // The filters are what keeps the fit clean: without the gradient and hue-saturation filters the
  // stripe and the occluder's pairs bias C far beyond that tolerance.
  ColourCompensationOptions open;
  open.maxGradient = INFINITY;
  open.maxHsDistance = INFINITY;
  const ColourCompensation biased =
      estimateColourCompensation(s.camera, s.rendering, s.coverage, open);
  std::printf("same scene without filters: largest error per element %.3g\n",
              maxError(biased.matrix, truth));
  EXPECT_GT(maxError(biased.matrix, truth), 1e-2);
}

// The fine filter against the previous estimate: a shadow in the photograph that the scan does not
// have keeps hue and saturation (the coarse filter and eq. 1's weights cannot see it) but halves
// the brightness. With c_{t-1} = C_true its inner pixels differ from the rendering by at least
// 0.5 * 0.25 in value and are rejected at 0.1; without it they bias C.
TEST(ColourCompensation, PreviousEstimateRejectsBrightnessOutliers) {
  const Eigen::Matrix3d truth = trueTransform();
  PhotoPair s = makePhotoPair(truth);
  for (int y = 40; y < 120; y++) {
    for (int x = 40; x < 136; x++) setPixel(s.camera, x, y, 0.5 * pixel(s.camera, x, y));
  }
  ColourCompensationOptions options;
  options.maxHsvDistance = 0.1;
  const ColourCompensation fine =
      estimateColourCompensation(s.camera, s.rendering, s.coverage, options, truth);
  EXPECT_EQ(fine.statistics.hsvDistance, 94u * 78u);
  EXPECT_EQ(fine.statistics.hsDistance, 0u);
  ASSERT_FALSE(fine.approximated);
  EXPECT_LT(maxError(fine.matrix, truth), 1e-3);

  const ColourCompensation coarse =
      estimateColourCompensation(s.camera, s.rendering, s.coverage, options);
  EXPECT_EQ(coarse.statistics.hsvDistance, 0u);
  std::printf("shadow: error with previous estimate %.3g, without %.3g\n",
              maxError(fine.matrix, truth), maxError(coarse.matrix, truth));
  EXPECT_GT(maxError(coarse.matrix, truth), 1e-2);
}

// Eq. (1) and (2) on hand-made pairs: three primaries mapped to twice themselves (distance 0,
// weight 1), and one more red pair mapped to four times itself at distance 0.5, which weighs
// 0.5^2 = 1/4 in A and 0.5^8 = 1/256 in C. Worked by hand:
//   A_rr = (2 + 4/4) / (1 + 1/4) = 2.4, A_gg = A_bb = 2;
//   C_rr = (2 + 4/256 + gamma A_rr) / (1 + 1/256 + gamma), the rest of C = 2 I (diagonal data).
TEST(ColourCompensation, WeightsFollowEquationOne) {
  const std::vector<ColourPair> pairs = {{{1, 0, 0}, {2, 0, 0}, 0.0},
                                         {{0, 1, 0}, {0, 2, 0}, 0.0},
                                         {{0, 0, 1}, {0, 0, 2}, 0.0},
                                         {{1, 0, 0}, {4, 0, 0}, 0.5}};
  ColourCompensationOptions options;
  options.minPairs = 4;
  for (const double gamma : {0.0, 0.05}) {
    options.regularisation = gamma;
    const ColourCompensation c = fitColourCompensation(pairs, options);
    ASSERT_FALSE(c.approximated);
    EXPECT_NEAR(c.approximation(0, 0), 2.4, 1e-12);
    EXPECT_NEAR(c.approximation(1, 1), 2.0, 1e-12);
    Eigen::Matrix3d expected = 2 * Eigen::Matrix3d::Identity();
    expected(0, 0) = (2 + 4.0 / 256 + gamma * 2.4) / (1 + 1.0 / 256 + gamma);
    EXPECT_LT(maxError(c.matrix, expected), 1e-12) << "gamma " << gamma;
  }
  // A pair at distance 1 or more weighs nothing.
  const ColourCompensation far = fitColourCompensation({{{1, 1, 1}, {3, 3, 3}, 1.0}});
  EXPECT_FALSE(far.usable);
}

// Test 4. 40x40 = 1600 pairs, fewer than n = 2000: the per-channel scale is used, and for a
// photograph that differs by a pure per-channel scale it is exact (every pair has r_c / u_c = s_c,
// so the weighted ratio is s_c whatever the weights), up to float storage: 1e-6.
TEST(ColourCompensation, FewPairsFallBackToTheChannelScale) {
  const Eigen::Vector3d scale(1.4, 1.1, 0.7);
  const Eigen::Matrix3d truth = scale.asDiagonal();
  const PhotoPair s = makePhotoPair(truth, 40, 40);
  const ColourCompensation c = estimateColourCompensation(s.camera, s.rendering, s.coverage);
  EXPECT_EQ(c.statistics.accepted, 1600u);
  EXPECT_TRUE(c.usable);
  EXPECT_TRUE(c.approximated);
  EXPECT_EQ(c.matrix, c.approximation);
  EXPECT_LT(maxError(c.matrix, truth), 1e-6);
  EXPECT_EQ(c.matrix(0, 1), 0.0);
  EXPECT_EQ(c.matrix(2, 0), 0.0);
  EXPECT_LT(
      maxError(c.inverse, Eigen::Vector3d(1 / 1.4, 1 / 1.1, 1 / 0.7).asDiagonal().toDenseMatrix()),
      1e-6);

  // The same pairs with the threshold lowered fit the linear map, which is diagonal here too.
  ColourCompensationOptions options;
  options.minPairs = 1000;
  const ColourCompensation linear =
      estimateColourCompensation(s.camera, s.rendering, s.coverage, options);
  EXPECT_FALSE(linear.approximated);
  EXPECT_LT(maxError(linear.matrix, truth), 1e-3);
}

// Pairs that span only the grey axis leave U W^2 U^T singular without regularisation: C is then
// not trusted and A is used. With the paper's gamma the unconstrained directions follow A.
TEST(ColourCompensation, DegeneratePairsFallBackWithoutRegularisation) {
  PhotoPair s{HdrImage(kWidth, kHeight), HdrImage(kWidth, kHeight), {}};
  for (int y = 0; y < kHeight; y++) {
    for (int x = 0; x < kWidth; x++) {
      const double g = 0.3 + 0.3 * x / double(kWidth);
      setPixel(s.rendering, x, y, {g, g, g});
      setPixel(s.camera, x, y, encode(decode({g, g, g}) / 1.5));
    }
  }
  ColourCompensationOptions options;
  options.regularisation = 0;
  const ColourCompensation c =
      estimateColourCompensation(s.camera, s.rendering, s.coverage, options);
  EXPECT_TRUE(c.usable);
  EXPECT_TRUE(c.approximated);
  EXPECT_EQ(c.matrix, c.approximation);
  EXPECT_LT(maxError(c.matrix, 1.5 * Eigen::Matrix3d::Identity()), 1e-5);

  const ColourCompensation r = estimateColourCompensation(s.camera, s.rendering, s.coverage);
  EXPECT_FALSE(r.approximated);
  EXPECT_LT(maxError(r.matrix, 1.5 * Eigen::Matrix3d::Identity()), 1e-4);
}

// Test 5. A black, a white and a NaN photograph: no pairs at all. The result is the identity,
// approximated and marked unusable (the frame carries no colour information), never NaN.
TEST(ColourCompensation, UnusablePhotographsGiveTheIdentity) {
  const PhotoPair base = makePhotoPair(trueTransform(), 64, 48);
  for (const float value : {0.0f, 1.0f, NAN}) {
    HdrImage camera(64, 48);
    std::fill(camera.rgb.begin(), camera.rgb.end(), value);
    const ColourCompensation c = estimateColourCompensation(camera, base.rendering, base.coverage);
    EXPECT_EQ(c.statistics.accepted, 0u);
    if (std::isnan(value)) {
      EXPECT_EQ(c.statistics.nonFinite, 64u * 48u);
    } else {
      EXPECT_EQ(c.statistics.saturated, 64u * 48u);
    }
    EXPECT_TRUE(c.approximated);
    EXPECT_FALSE(c.usable);
    EXPECT_EQ(c.matrix, Eigen::Matrix3d::Identity());
    EXPECT_EQ(c.inverse, Eigen::Matrix3d::Identity());
    EXPECT_TRUE(c.approximation.allFinite());
    EXPECT_TRUE(std::isfinite(c.conditionNumber));
  }
  // No pairs at all, straight into the fit.
  EXPECT_FALSE(fitColourCompensation({}).usable);
}

TEST(ColourCompensation, MismatchedInputsThrow) {
  const PhotoPair s = makePhotoPair(trueTransform(), 16, 16);
  EXPECT_THROW(selectColourPairs(s.camera, HdrImage(16, 8), {}), Error);
  EXPECT_THROW(selectColourPairs(s.camera, s.rendering, std::vector<uint8_t>(10, 1)), Error);
}

}  // namespace
}  // namespace nestlight::gi::hdr
