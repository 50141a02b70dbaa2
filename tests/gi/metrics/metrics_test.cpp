// Image error metrics against cases whose answer is known without the code under test: identical
// images, constant offsets and scales, hand-computed tiny images, SSIM's closed form on flat
// images and its direct (non-separable) definition, non-finite pixels, sizes that differ and
// values beyond half-float range. SSIM: Wang et al., IEEE TIP 13(4), 2004.
#include "nestlight/gi/metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "nestlight/gi/sampling.h"
#include "nestlight/gi/tone_map.h"
#include "test_support.h"

using namespace nestlight::gi;
using nestlight::test::errorOf;
using nestlight::test::readFile;
using nestlight::test::TempDir;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

HdrImage randomImage(int w, int h, float scale, uint64_t seed) {
  HdrImage img(w, h);
  Rng rng(seed);
  for (float& v : img.rgb) v = scale * rng.uniform();
  return img;
}

// Values that are multiples of 1/64 below 8: sums, squares and means of these and of offsets
// like 1/8 are exact in double, so the metrics of offsets must come out exact, not just close.
HdrImage dyadicImage(int w, int h) {
  HdrImage img(w, h);
  for (size_t i = 0; i < img.rgb.size(); ++i) img.rgb[i] = float((i * 37) % 512) / 64.0f;
  return img;
}

double standardNormal(Rng& rng) {
  // Box-Muller; 1 - u keeps the logarithm's argument in (0, 1].
  const double u1 = 1.0 - rng.uniform(), u2 = rng.uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * 3.14159265358979323846 * u2);
}

// SSIM at (x, y) straight from Wang et al.'s definition with a 2D window, truncated at the
// border and at non-finite pixels and renormalised: the convention metrics.h states.
double directSsimAt(const HdrImage& a, const HdrImage& b, int x, int y, double L) {
  const double c1 = (0.01 * L) * (0.01 * L), c2 = (0.03 * L) * (0.03 * L);
  double s = 0;
  for (int c = 0; c < 3; ++c) {
    double w = 0, ma = 0, mb = 0, aa = 0, bb = 0, ab = 0;
    for (int dy = -5; dy <= 5; ++dy)
      for (int dx = -5; dx <= 5; ++dx) {
        const int xx = x + dx, yy = y + dy;
        if (xx < 0 || yy < 0 || xx >= a.width || yy >= a.height) continue;
        const Rgb pa = a.get(xx, yy), pb = b.get(xx, yy);
        bool finite = true;
        for (int k = 0; k < 3; ++k) finite = finite && std::isfinite(pa[k]) && std::isfinite(pb[k]);
        if (!finite) continue;
        const double g = std::exp(-(dx * dx + dy * dy) / (2 * 1.5 * 1.5));
        const double va = pa[c], vb = pb[c];
        w += g, ma += g * va, mb += g * vb, aa += g * va * va, bb += g * vb * vb, ab += g * va * vb;
      }
    ma /= w, mb /= w;
    const double sa = aa / w - ma * ma, sb = bb / w - mb * mb, sab = ab / w - ma * mb;
    s += (2 * ma * mb + c1) * (2 * sab + c2) / ((ma * ma + mb * mb + c1) * (sa + sb + c2));
  }
  return s / 3;
}

}  // namespace

TEST(Metrics, IdenticalImagesHaveZeroErrorInfinitePsnrAndSsimOne) {
  const HdrImage img = randomImage(37, 23, 10.0f, 1);
  const ImageComparison c = compareImages(img, img);
  EXPECT_EQ(c.pixels, 37u * 23u);
  EXPECT_EQ(c.compared, c.pixels);
  for (const ErrorStats* s : {&c.linear, &c.toneMapped}) {
    EXPECT_EQ(s->mse, 0);
    EXPECT_EQ(s->rmse, 0);
    EXPECT_EQ(s->meanAbsolute, 0);
    EXPECT_EQ(s->maxAbsolute, 0);
    EXPECT_EQ(s->relativeMse, 0);
    EXPECT_EQ(s->meanRelative, 0);
    EXPECT_TRUE(std::isinf(s->psnr) && s->psnr > 0) << s->psnr;
    // With equal inputs numerator and denominator of SSIM are the same products (2xy == x^2+y^2
    // when x == y, both exact doublings of one rounded product), so each ratio is exactly 1 and
    // only the averaging can round: 1e-12 allows for that.
    EXPECT_NEAR(s->ssim, 1.0, 1e-12);
  }
  EXPECT_FLOAT_EQ(c.toneMapped.peak, 1.0);
  EXPECT_EQ(toJson(c)["linear"]["psnr_db"], "inf");
}

TEST(Metrics, ConstantOffsetGivesRmseExactly) {
  const HdrImage b = dyadicImage(16, 9);
  for (float d : {0.125f, -0.5f, 3.0f}) {
    HdrImage a = b;
    for (float& v : a.rgb) v += d;
    const ImageComparison c = compareImages(a, b);
    // Exact (no tolerance): every value and every partial sum is a dyadic rational that double
    // holds exactly (see dyadicImage).
    EXPECT_EQ(c.linear.rmse, std::abs(d)) << d;
    EXPECT_EQ(c.linear.mse, double(d) * d) << d;
    EXPECT_EQ(c.linear.meanAbsolute, std::abs(d)) << d;
    EXPECT_EQ(c.linear.maxAbsolute, std::abs(d)) << d;
  }
}

TEST(Metrics, TinyImageMatchesHandComputedValues) {
  // Two pixels. Differences per channel: 0, 2, 0 | 0, 0, -4.
  HdrImage a(2, 1), b(2, 1);
  a.set(0, 0, {1, 2, 3}), a.set(1, 0, {0, 0, 0});
  b.set(0, 0, {1, 0, 3}), b.set(1, 0, {0, 0, 4});
  const ImageComparison c = compareImages(a, b);
  // Hand: MSE = (2^2 + 4^2) / 6 = 10/3; peak = reference max = 4; relMSE and mean relative
  // error have non-zero terms only where the difference is: 4/(0+0.01), 16/(16+0.01) and
  // 2/(0+0.01), 4/(4+0.01). 1e-12 relative: a few double roundings of the same sums.
  EXPECT_NEAR(c.linear.mse, 10.0 / 3.0, 1e-12);
  EXPECT_NEAR(c.linear.rmse, std::sqrt(10.0 / 3.0), 1e-12);
  EXPECT_NEAR(c.linear.rmse, 1.8257418583505538, 1e-12);
  EXPECT_EQ(c.linear.meanAbsolute, 1.0);
  EXPECT_EQ(c.linear.maxAbsolute, 4.0);
  EXPECT_EQ(c.linear.peak, 4.0);
  EXPECT_NEAR(c.linear.psnr, 10 * std::log10(16 / (10.0 / 3.0)), 1e-10);
  EXPECT_NEAR(c.linear.psnr, 6.812412373755872, 1e-10);  // 10 log10(4.8)
  EXPECT_NEAR(c.linear.relativeMse, (4 / 0.01 + 16 / 16.01) / 6, 1e-10);
  EXPECT_NEAR(c.linear.meanRelative, (2 / 0.01 + 4 / 4.01) / 6, 1e-10);
}

TEST(Metrics, RelativeMseOfScaledImageMatchesClosedForm) {
  // One pixel by hand: b = (0.5, 0.1, 2), a = 2b; terms b^2 / (b^2 + 0.01).
  HdrImage a(1, 1), b(1, 1);
  b.set(0, 0, {0.5f, 0.1f, 2.0f});
  a.set(0, 0, {1.0f, 0.2f, 4.0f});
  // 1e-7: 0.1f is not 0.1; its rounding (3e-9 relative) moves the second term by about that.
  EXPECT_NEAR(compareImages(a, b).linear.relativeMse, (0.25 / 0.26 + 0.01 / 0.02 + 4.0 / 4.01) / 3,
              1e-7);

  // A whole image, a = k b with k = 1.5: mean of (k-1)^2 b^2 / (b^2 + eps) per channel value.
  const double k = 1.5, eps = 1e-2;
  const HdrImage ref = randomImage(40, 30, 3.0f, 5);
  HdrImage test = ref;
  for (float& v : test.rgb) v = float(k * v);
  double expect = 0;
  for (float v : ref.rgb) expect += (k - 1) * (k - 1) * double(v) * v / (double(v) * v + eps);
  expect /= double(ref.rgb.size());
  // 1e-6 relative: storing k b as float rounds it by up to 6e-8 relative, which (k-1) b = b/2
  // magnifies 3 times and squaring doubles: under 4e-7.
  EXPECT_NEAR(compareImages(test, ref).linear.relativeMse, expect, 1e-6 * expect);
}

TEST(Metrics, SsimOfFlatImagesMatchesClosedForm) {
  // Flat images have zero variance, so SSIM = (2 ma mb + C1) / (ma^2 + mb^2 + C1) (the
  // contrast-structure factor is C2 / C2): a check of C1 = (K1 L)^2.
  for (double L : {1.0, 50.0}) {
    HdrImage a(9, 14), b(9, 14);
    for (float& v : a.rgb) v = 0.3f;
    for (float& v : b.rgb) v = 0.6f;
    const double c1 = (0.01 * L) * (0.01 * L);
    const double ma = 0.3f, mb = 0.6f;
    // 1e-12: the window means of a constant are the constant up to rounding in the weights.
    EXPECT_NEAR(ssim(a, b, L), (2 * ma * mb + c1) / (ma * ma + mb * mb + c1), 1e-12) << L;
  }
}

TEST(Metrics, SsimMatchesDirectWindowDefinition) {
  // The separable strip implementation against a plain 2D window at every pixel, on an image
  // smaller than two strips, with a non-finite pixel and borders on all sides.
  HdrImage a = randomImage(23, 35, 2.0f, 11), b = randomImage(23, 35, 2.0f, 12);
  a.set(7, 20, {kNaN, 0, 0});
  const double L = 2.0;
  double sum = 0;
  int n = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      if (x == 7 && y == 20) continue;
      sum += directSsimAt(a, b, x, y, L);
      ++n;
    }
  // 1e-12: the same sums in a different order.
  EXPECT_NEAR(ssim(a, b, L), sum / n, 1e-12);
}

TEST(Metrics, SsimDecreasesMonotonicallyWithNoise) {
  // A smooth image with some texture, and one fixed noise field scaled up: SSIM must fall at
  // each step, from 1 without noise.
  const int w = 64, h = 48;
  HdrImage base(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float g = 0.2f + 0.5f * float(x) / w + 0.1f * std::sin(0.7f * float(y));
      base.set(x, y, {g, 0.8f * g, 0.5f + 0.2f * std::cos(0.3f * float(x + y))});
    }
  Rng rng(99);
  std::vector<float> noise(base.rgb.size());
  for (float& n : noise) n = float(standardNormal(rng));
  double previous = 2;
  for (double sigma : {0.0, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0}) {
    HdrImage noisy = base;
    for (size_t i = 0; i < noisy.rgb.size(); ++i) noisy.rgb[i] += float(sigma) * noise[i];
    const double s = ssim(noisy, base, 1.0);
    if (sigma == 0) {
      EXPECT_NEAR(s, 1.0, 1e-12);
    }
    EXPECT_LT(s, previous) << "sigma " << sigma;
    EXPECT_GT(s, -1.0);
    previous = s;
  }
  EXPECT_LT(previous, 0.2);  // noise with sigma 1 on a [0, 1] image leaves little structure
}

TEST(Metrics, SsimIsSymmetric) {
  const HdrImage a = randomImage(31, 17, 4.0f, 21), b = randomImage(31, 17, 4.0f, 22);
  // Exact: every term of SSIM is symmetric in (a, b) and floating-point + and * commute.
  EXPECT_EQ(ssim(a, b, 4.0), ssim(b, a, 4.0));
  // Tone-mapped SSIM has L = 1 either way, so compareImages' is symmetric too (the linear one
  // takes L from whichever image is the reference, and so is not).
  EXPECT_EQ(compareImages(a, b).toneMapped.ssim, compareImages(b, a).toneMapped.ssim);
  const double s = ssim(a, b, 4.0);
  EXPECT_GT(s, -1.0);
  EXPECT_LT(s, 1.0);
}

TEST(Metrics, NonFinitePixelsAreCountedAndLeftOut) {
  const HdrImage ref0 = dyadicImage(8, 8);
  HdrImage test = ref0, ref = ref0;
  for (float& v : test.rgb) v += 0.25f;
  test.set(1, 1, {0, kNaN, 0});
  test.set(2, 2, {kInf, 0, 0});
  ref.set(2, 2, {-kInf, 0, 0});
  ref.set(5, 5, {kNaN, kNaN, kNaN});
  const ImageComparison c = compareImages(test, ref);
  EXPECT_EQ(c.test.pixels, 2u);
  EXPECT_EQ(c.test.nan, 1u);
  EXPECT_EQ(c.test.inf, 1u);
  EXPECT_EQ(c.reference.pixels, 2u);
  EXPECT_EQ(c.reference.nan, 3u);
  EXPECT_EQ(c.reference.inf, 1u);
  EXPECT_EQ(c.compared, 64u - 3u);  // pixel (2,2) is bad in both
  // Every other pixel is off by exactly 1/4, so nothing non-finite leaked into the numbers.
  EXPECT_EQ(c.linear.rmse, 0.25);
  EXPECT_EQ(c.linear.maxAbsolute, 0.25);
  for (double v :
       {c.linear.ssim, c.linear.relativeMse, c.linear.psnr, c.toneMapped.rmse, c.toneMapped.ssim})
    EXPECT_TRUE(std::isfinite(v)) << v;

  // Nothing comparable: every number is NaN, not 0 (which would read as "perfect").
  HdrImage allNaN(4, 4);
  for (float& v : allNaN.rgb) v = kNaN;
  const ImageComparison none = compareImages(allNaN, HdrImage(4, 4));
  EXPECT_EQ(none.compared, 0u);
  EXPECT_EQ(none.test.pixels, 16u);
  EXPECT_TRUE(std::isnan(none.linear.rmse));
  EXPECT_TRUE(std::isnan(none.linear.ssim));
  EXPECT_TRUE(std::isnan(none.toneMapped.psnr));
  EXPECT_EQ(toJson(none)["linear"]["rmse"], "nan");
}

TEST(Metrics, SizeMismatchIsAnErrorNamingBothFiles) {
  CompareOptions o;
  o.testName = "render.exr";
  o.referenceName = "reference.exr";
  const nestlight::Error e = errorOf([&] { compareImages(HdrImage(4, 4), HdrImage(4, 5), o); });
  EXPECT_EQ(e.file(), "render.exr");
  EXPECT_NE(std::string(e.what()).find("reference.exr"), std::string::npos) << e.what();
  EXPECT_NE(std::string(e.what()).find("4x5"), std::string::npos) << e.what();
  errorOf([&] { errorFalseColour(HdrImage(3, 2), HdrImage(2, 3), {}, o); });
  errorOf([&] { ssim(HdrImage(3, 2), HdrImage(2, 3), 1.0); });
}

TEST(Metrics, ValuesBeyondHalfFloatRangeDoNotOverflow) {
  // Integers up to 2^24 are exact in float, so the offset is exact and RMSE must be 1e5 exactly.
  HdrImage ref(12, 12), test(12, 12);
  for (size_t i = 0; i < ref.rgb.size(); ++i) ref.rgb[i] = 70000.0f + float(i * 1000);
  for (size_t i = 0; i < ref.rgb.size(); ++i) test.rgb[i] = ref.rgb[i] + 100000.0f;
  ImageComparison c = compareImages(test, ref);
  EXPECT_EQ(c.linear.rmse, 100000.0);
  EXPECT_EQ(c.linear.peak, double(ref.rgb.back()));
  EXPECT_TRUE(std::isfinite(c.linear.psnr));
  EXPECT_GT(c.linear.ssim, -1.0);
  EXPECT_LT(c.linear.ssim, 1.0);
  // Both clip to white after the tone map: no visible difference.
  EXPECT_EQ(c.toneMapped.rmse, 0);

  // Near FLT_MAX the difference (6e38) and its square exist only in double.
  test.set(3, 4, {3e38f, 3e38f, 3e38f});
  ref.set(3, 4, {-3e38f, -3e38f, -3e38f});
  c = compareImages(test, ref);
  EXPECT_EQ(c.compared, c.pixels);
  EXPECT_NEAR(c.linear.maxAbsolute, 6e38, 1e32);
  for (double v : {c.linear.mse, c.linear.rmse, c.linear.relativeMse, c.linear.meanRelative,
                   c.linear.psnr, c.linear.ssim, c.toneMapped.rmse, c.toneMapped.ssim})
    EXPECT_TRUE(std::isfinite(v)) << v;
  EXPECT_TRUE(std::isfinite(ssim(test, ref, 3e38)));
}

TEST(Metrics, FalseColourImageHasInputSizeAndMapsTheLegend) {
  const int w = 7, h = 5;
  HdrImage ref(w, h), test(w, h);
  for (float& v : ref.rgb) v = 1.0f;
  test = ref;
  // (1,0): relative error 10^-1.5, the middle of the default log range [1e-3, 1];
  // (2,0): 100, beyond the top; (3,0): NaN; everything else exact.
  const float mid = float(std::pow(10.0, -1.5) * 1.01);  // |t - r| / (1 + 0.01) = 10^-1.5
  test.set(1, 0, Rgb(1.0f + mid));
  test.set(2, 0, Rgb(102.0f));
  test.set(3, 0, {kNaN, 1, 1});
  const HdrImage fc = errorFalseColour(test, ref);
  ASSERT_EQ(fc.width, w);
  ASSERT_EQ(fc.height, h);
  auto expectColour = [&](int x, int y, Rgb want) {
    const Rgb got = fc.get(x, y);
    // 1e-4: float rounding of the viridis interpolation; colours are written with 1/255 steps.
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(got[k], want[k], 1e-4) << x << "," << y << " channel " << k;
  };
  expectColour(0, 0, Rgb(68, 1, 84) / 255.0f);     // zero error: bottom of viridis
  expectColour(1, 0, viridis(0.5));                // the range's middle
  expectColour(2, 0, Rgb(253, 231, 37) / 255.0f);  // clamped to the top
  expectColour(3, 0, Rgb(1, 0, 1));                // non-finite: magenta
  expectColour(4, 4, Rgb(68, 1, 84) / 255.0f);

  TempDir t;
  const ErrorImageLegend legend = writeErrorImage(t.file("err.png"), test, ref);
  const std::string png = readFile(t.file("err.png"));
  ASSERT_GE(png.size(), 24u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  // IHDR: big-endian width and height at bytes 16 and 20.
  auto be32 = [&](size_t at) {
    return (uint32_t(uint8_t(png[at])) << 24) | (uint32_t(uint8_t(png[at + 1])) << 16) |
           (uint32_t(uint8_t(png[at + 2])) << 8) | uint32_t(uint8_t(png[at + 3]));
  };
  EXPECT_EQ(be32(16), uint32_t(w));
  EXPECT_EQ(be32(20), uint32_t(h));
  EXPECT_EQ(legend.minRelative, 1e-3);
  EXPECT_EQ(legend.maxRelative, 1.0);
  EXPECT_NE(legend.describe().find("viridis"), std::string::npos);
  EXPECT_NE(legend.describe().find("0.001"), std::string::npos);

  ErrorImageOptions bad;
  bad.minRelative = 1, bad.maxRelative = 0.1;
  errorOf([&] { errorFalseColour(test, ref, bad); });
  errorOf([&] { writeErrorImage(t.file("no/such/dir/err.png"), test, ref); });
}

TEST(ToneMap, SrgbCurveExposureAndNonFinite) {
  // IEC 61966-2-1 values; 1e-6 is a few float ulps at these magnitudes.
  EXPECT_EQ(srgbEncode(0), 0);
  EXPECT_NEAR(srgbEncode(1), 1, 1e-6);
  EXPECT_NEAR(srgbEncode(0.0031308f), 0.04045f, 1e-6);
  EXPECT_NEAR(srgbEncode(0.5f), 0.7353569830524495, 1e-6);
  EXPECT_NEAR(srgbEncode(0.18f), 0.4613561295004745, 1e-6);
  for (float v : {0.001f, 0.01f, 0.2f, 0.7f, 1.0f})
    EXPECT_NEAR(srgbDecode(srgbEncode(v)), v, 2e-6 * (1 + v));
  EXPECT_NEAR(toneMapValue(0.25f, exposureScale(1)), srgbEncode(0.5f), 1e-7);  // +1 stop doubles
  EXPECT_NEAR(toneMapValue(2.0f, exposureScale(-1)), 1.0f, 1e-6);
  EXPECT_EQ(toneMapValue(70000.0f, 1), 1.0f);
  EXPECT_EQ(toneMapValue(kInf, 1), 1.0f);
  EXPECT_EQ(toneMapValue(-kInf, 1), 0.0f);
  EXPECT_EQ(toneMapValue(-3.0f, 1), 0.0f);
  EXPECT_TRUE(std::isnan(toneMapValue(kNaN, 1)));

  HdrImage img(3, 2);
  img.set(0, 0, {0.5f, 1e6f, kNaN});
  const HdrImage tm = toneMap(img, 0);
  EXPECT_EQ(tm.width, 3);
  EXPECT_EQ(tm.height, 2);
  EXPECT_NEAR(tm.get(0, 0)[0], srgbEncode(0.5f), 1e-7);
  EXPECT_EQ(tm.get(0, 0)[1], 1.0f);
  EXPECT_TRUE(std::isnan(tm.get(0, 0)[2]));
  TempDir t;
  writeToneMappedPng(t.file("x.png"), img, 0);  // the NaN pixel is written magenta, not rejected
  EXPECT_EQ(readFile(t.file("x.png")).substr(1, 3), "PNG");
}
