// Environment maps (gi/core/src/environment_map.cpp) and HDR image I/O (hdr_image.cpp): the
// lat-long convention, the sampler against its pdf by chi-square, irradiance estimates against
// analytic values, black maps, values beyond half float, invalid texels, Radiance .hdr and EXR
// round trips, errors that name the file, and the real maps in the shared data folder.
#include "nestlight/gi/environment_map.h"

#include <gtest/gtest.h>
#include <stb/stb_image_write.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "gi/chi2.h"
#include "nestlight/gi/hdr_image.h"
#include "nestlight/octree/error.h"
#include "test_support.h"

using namespace nestlight::gi;
using namespace nestlight::gi::chi2;

namespace {

// A fresh folder removed at the end of the test (tests/test_support.h has one too, but it pulls
// in the converters library; these tests need only gi).
class ScratchDir {
 public:
  ScratchDir() {
    static int counter = 0;
    path_ = std::filesystem::temp_directory_path() /
            ("nestlight_env_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

// The direction through the centre of texel (x, y) of a w x h map, from the convention as the
// header states it (phi = 2 pi u from +x towards +y, theta = pi v from +z), written out here
// independently of the code under test.
glm::vec3 texelCentre(int x, int y, int w, int h, float rotationDegrees = 0) {
  double phi = 2 * M_PI * (x + 0.5) / w + rotationDegrees * M_PI / 180,
         theta = M_PI * (y + 0.5) / h;
  return glm::vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                   std::cos(theta));
}

// cos theta at the top and bottom edges of row y.
double rowCos(int y, int h) {
  return std::cos(M_PI * y / h);
}

// Irradiance on an upward plane, E = integral over the upper hemisphere of L cos, for a map whose
// radiance is constant per texel: each texel contributes L (2 pi / w) (c0^2 - c1^2) / 2.
Rgb analyticIrradiance(const HdrImage& img) {
  glm::dvec3 e(0.0);
  for (int y = 0; y < img.height; ++y) {
    double c0 = std::max(0.0, rowCos(y, img.height)), c1 = std::max(0.0, rowCos(y + 1, img.height));
    for (int x = 0; x < img.width; ++x)
      e += glm::dvec3(img.get(x, y)) * (2 * M_PI / img.width * (c0 * c0 - c1 * c1) / 2);
  }
  return Rgb(e);
}

// The importance-sampled estimator of that irradiance.
Rgb estimateIrradiance(const EnvironmentMap& env, int n, uint64_t seed) {
  Rng rng(seed);
  glm::dvec3 sum(0.0);
  for (int i = 0; i < n; ++i) {
    EnvironmentMap::Sample s = env.sample(rng.uniform2());
    if (s.pdf > 0 && s.direction.z > 0)
      sum += glm::dvec3(s.radiance) * double(s.direction.z / s.pdf);
  }
  return Rgb(sum / double(n));
}

// The estimator's relative standard deviation for one sample, channel k. The density is
// lum_t / P per solid angle in texel t (P = sum of luminance * solid angle), so a sample in t is
// X = P (L_t / lum_t) cos+, and E[X^2] = P sum_t (L_t^2 / lum_t) integral_t cos+^2, where
// integral_t cos+^2 = (2 pi / w) (c0^3 - c1^3) / 3 over the upper part of the row.
double relativeSigmaPerSample(const HdrImage& img, int k = 1) {
  double p = 0, e = 0, e2 = 0;
  for (int y = 0; y < img.height; ++y) {
    double c0 = rowCos(y, img.height), c1 = rowCos(y + 1, img.height);
    double u0 = std::max(0.0, c0), u1 = std::max(0.0, c1), dphi = 2 * M_PI / img.width;
    for (int x = 0; x < img.width; ++x) {
      double lum = luminance(img.get(x, y)), l = img.get(x, y)[k];
      if (!(lum > 0)) continue;
      p += lum * dphi * (c0 - c1);
      e += l * dphi * (u0 * u0 - u1 * u1) / 2;
      e2 += l * l / lum * dphi * (u0 * u0 * u0 - u1 * u1 * u1) / 3;
    }
  }
  return std::sqrt(p * e2 - e * e) / e;
}

HdrImage structuredMap(int w, int h) {
  // Sky brightening towards the horizon, a coloured ramp in azimuth, a black wedge, a small sun,
  // a dim ground: zeros, smooth parts and a 1e3 contrast in one map.
  HdrImage img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float t = float(x) / w;
      Rgb c = y < h / 2 ? Rgb(0.5f + t, 1.0f, 1.5f - t) * (1.0f + 3.0f * y / h)
                        : Rgb(0.2f, 0.15f, 0.1f) * (1.0f + t);
      if (x >= w / 8 && x < w / 4) c = Rgb(0.0f);
      if (x >= 40 * w / 64 && x < 43 * w / 64 && y >= 6 * h / 32 && y < 8 * h / 32)
        c = Rgb(5000.0f, 4500.0f, 4000.0f);
      img.set(x, y, c);
    }
  return img;
}

}  // namespace

TEST(EnvironmentMap, ConventionTexelsAndRotation) {
  const int w = 8, h = 4;
  HdrImage img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.set(x, y, Rgb(float(x + 1), float(y + 1), 1.0f));
  EnvironmentMap env(img);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      EXPECT_EQ(env.eval(texelCentre(x, y, w, h)), img.get(x, y)) << x << "," << y;

  // +z is the top row; -z the bottom row.
  EXPECT_EQ(env.eval({0.01f, 0.002f, 1}), img.get(0, 0));
  EXPECT_EQ(env.eval({0, 0, 1}), img.get(0, 0));
  EXPECT_EQ(env.eval({0.01f, 0.002f, -1}), img.get(0, h - 1));
  // +x (a little above the horizon, a little towards +y) is column 0; +y is u = 0.25, the
  // first column of the second quarter; -x is u = 0.5.
  const glm::vec3 nearX = glm::normalize(glm::vec3(1, 0.01f, 0.1f)),
                  nearY = glm::normalize(glm::vec3(-0.01f, 1, 0.1f));
  EXPECT_EQ(env.eval(nearX), img.get(0, 1));
  EXPECT_EQ(env.eval(nearY), img.get(w / 4, 1));
  EXPECT_EQ(env.eval(glm::normalize(glm::vec3(-1, -0.01f, 0.1f))), img.get(w / 2, 1));
  // Just below +x (phi -> 2 pi) is the last column, not past it.
  EXPECT_EQ(env.eval(glm::normalize(glm::vec3(1, -1e-7f, 0.1f))), img.get(w - 1, 1));

  // Rotating by +90 degrees (counter-clockwise from above) carries what was seen towards +x to +y.
  EnvironmentMap rotated(img, 90);
  EXPECT_EQ(rotated.eval(nearY), env.eval(nearX));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) EXPECT_EQ(rotated.eval(texelCentre(x, y, w, h, 90)), img.get(x, y));

  // `scale` multiplies radiance and leaves the sampling density alone.
  EnvironmentMap scaled(img, 0, 2.5f);
  const glm::vec3 d = texelCentre(3, 2, w, h);
  EXPECT_EQ(scaled.eval(d), 2.5f * img.get(3, 2));
  EXPECT_EQ(scaled.pdf(d), env.pdf(d));
  EXPECT_EQ(env.invalidTexels(), 0u);
  EXPECT_FALSE(env.black());

  // Non-finite or zero directions see nothing rather than an arbitrary texel.
  EXPECT_EQ(env.eval(glm::vec3(NAN, 0, 1)), Rgb(0.0f));
  EXPECT_EQ(env.pdf(glm::vec3(0.0f)), 0.0f);
}

TEST(EnvironmentMap, SamplerMatchesPdfChiSquare) {
  // Texels and chi-square bins coincide (64 x 32 texels, 64 phi x 32 theta bins) without
  // rotation; at 37 degrees texel edges cut through bins in phi and the quadrature resolves them.
  const HdrImage img = structuredMap(64, 32);
  const float rotations[] = {0.0f, 37.0f};
  Chi2Options o;
  o.tests = int(std::size(rotations));
  for (float rot : rotations) {
    EnvironmentMap env(img, rot);
    auto sampler = [&](Rng& rng) -> std::optional<glm::vec3> {
      EnvironmentMap::Sample s = env.sample(rng.uniform2());
      if (!(s.pdf > 0)) return std::nullopt;
      return s.direction;
    };
    Chi2Result r = chi2Test(
        sampler, [&](const glm::vec3& d) { return double(env.pdf(d)); }, o);
    EXPECT_TRUE(r.passed) << "rotation " << rot << ": " << r.message;
    // The pdf integrates to 1 and the sampler rejects nothing. 1e-5: the quadrature's 1e-6
    // relative per bin, and float pdfs summed over 2048 bins.
    EXPECT_NEAR(r.pdfIntegral, 1.0, 1e-5) << rot;
    EXPECT_EQ(r.failedSamples, 0u) << rot;
    std::printf("environment rotation %g: %s\n", rot,
                r.message.substr(0, r.message.find(';')).c_str());
  }
}

TEST(EnvironmentMap, SampleAgreesWithPdfAndEval) {
  const HdrImage img = structuredMap(64, 32);
  EnvironmentMap env(img, 20);
  // Sum of pdf * solid angle over texel centres: the density is constant per texel, so this is
  // exactly 1 up to float rounding of each pdf (1e-6 relative, with margin).
  double sum = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 64; ++x)
      sum += env.pdf(texelCentre(x, y, 64, 32, 20)) * (2 * M_PI / 64) *
             (rowCos(y, 32) - rowCos(y + 1, 32));
  EXPECT_NEAR(sum, 1.0, 1e-5);
  Rng rng(9);
  for (int i = 0; i < 100000; ++i) {
    glm::vec2 u = rng.uniform2();
    if (i == 0) u = {0, 0};
    if (i == 1) u = {kOneMinusEpsilon, kOneMinusEpsilon};
    EnvironmentMap::Sample s = env.sample(u);
    // sin and cos computed in double, rounded to float: |d| = 1 within 1e-7; 1e-5 with margin.
    ASSERT_NEAR(glm::length(s.direction), 1, 1e-5);
    // Exactly equal: MIS computes the light pdf of a BSDF-sampled direction with pdf().
    ASSERT_EQ(s.pdf, env.pdf(s.direction));
    ASSERT_EQ(s.radiance, env.eval(s.direction));
    // Only texels with radiance are sampled (a rounding across a texel edge may land on a black
    // neighbour: then pdf and radiance are both 0 and the tracer skips the sample).
    ASSERT_EQ(s.pdf > 0, luminance(s.radiance) > 0);
  }
}

TEST(EnvironmentMap, ConstantMapIsUniformAndGivesPiL) {
  const Rgb L(0.5f, 1.0f, 2.0f);
  EnvironmentMap env = EnvironmentMap::constant(L);
  EXPECT_EQ(env.image().width, 1);
  EXPECT_EQ(env.image().height, 1);
  Rng rng(4);
  for (int i = 0; i < 1000; ++i) {
    EnvironmentMap::Sample s = env.sample(rng.uniform2());
    EXPECT_NEAR(s.pdf, 1 / (4 * M_PI), 1e-7);  // 1/(4 pi) = 0.08 rounded to float: 5e-9
    EXPECT_EQ(s.radiance, L);
  }
  // A sample is 4 pi L cos+ over the uniform sphere: relative sigma sqrt(16/6 - 1) = 1.29 per
  // sample, 2.0% for 4096; 5 sigma = 10% fails by chance with p < 6e-7. The seeded run is 0.5%.
  const int n = 4096;
  HdrImage one(1, 1);
  one.set(0, 0, L);
  const double sigma = relativeSigmaPerSample(one) / std::sqrt(double(n));
  EXPECT_NEAR(sigma, std::sqrt(5.0 / 3.0) / 64, 1e-6);  // the texel-sum formula, checked (double)
  Rgb e = estimateIrradiance(env, n, 1);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(e[k], M_PI * L[k], 5 * sigma * M_PI * L[k]) << k;
  std::printf("constant map: E/(pi L) = %.4f (bound 1 +- %.3f)\n", e.g / (M_PI * L.g), 5 * sigma);
}

TEST(EnvironmentMap, SunAndSkyIrradianceConverges) {
  // A sky of 1 over a ground of 0.3, and a sun 1e5 times the sky in one texel at 45 degrees.
  const int w = 128, h = 64;
  HdrImage img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.set(x, y, Rgb(y < h / 2 ? 1.0f : 0.3f));
  img.set(77, 16, Rgb(1e5f));
  for (float rot : {0.0f, 123.0f}) {
    EnvironmentMap env(img, rot);
    const Rgb exact = analyticIrradiance(img);  // rotation about z leaves it unchanged
    const int n = 4096;
    // The sun carries 98% of the power and its cos varies little across its texel, so the
    // importance-sampled estimator is nearly exact: sigma, computed from the texel sums, is
    // 0.22% for 4096 samples; the bound is 5 sigma = 1.1% (the seeded run is within 2e-4).
    const double sigma = relativeSigmaPerSample(img) / std::sqrt(double(n));
    // Importance sampling must make the estimate tight, not only unbiased: a 4096-sample
    // relative error above 2.5% (5 sigma at 0.5%) would mean the sun is not being found.
    EXPECT_LT(sigma, 0.005);
    Rgb e = estimateIrradiance(env, n, 2);
    EXPECT_NEAR(e.g, exact.g, 5 * sigma * exact.g) << rot;
    std::printf(
        "sun and sky, rotation %g: E = %.2f, exact %.2f, relative error %.2e (bound %.2e)\n", rot,
        e.g, exact.g, std::abs(e.g / exact.g - 1), 5 * sigma);
  }
}

TEST(EnvironmentMap, BlackMapsAreNeverSampled) {
  std::vector<EnvironmentMap> maps;
  maps.emplace_back();                                         // default: no image at all
  maps.push_back(EnvironmentMap(HdrImage(16, 8)));             // all zero
  maps.push_back(EnvironmentMap::constant(Rgb(0.0f)));         // zero constant
  maps.push_back(EnvironmentMap(structuredMap(16, 8), 0, 0));  // scale 0
  for (const EnvironmentMap& env : maps) {
    EXPECT_TRUE(env.black());
    Rng rng(1);
    for (int i = 0; i < 100; ++i) {
      EnvironmentMap::Sample s = env.sample(rng.uniform2());
      EXPECT_EQ(s.pdf, 0.0f);
      EXPECT_EQ(s.radiance, Rgb(0.0f));
      EXPECT_TRUE(std::isfinite(s.direction.x) && std::isfinite(s.direction.y) &&
                  std::isfinite(s.direction.z));
      glm::vec3 d = sampleUniformSphere(rng.uniform2());
      EXPECT_EQ(env.pdf(d), 0.0f);
      EXPECT_EQ(env.eval(d), Rgb(0.0f));
    }
  }
}

TEST(EnvironmentMap, InvalidTexelsAreCountedAndZeroed) {
  HdrImage img = structuredMap(32, 16);
  img.set(1, 1, Rgb(NAN, 1, 1));
  img.set(20, 3, Rgb(1, INFINITY, 1));
  img.set(21, 3, Rgb(1, 1, -INFINITY));
  img.set(30, 12, Rgb(-0.5f, 1, 1));
  img.set(31, 12, Rgb(-0.0f, 1, 1));  // negative zero is zero, not invalid
  EnvironmentMap env(img);
  EXPECT_EQ(env.invalidTexels(), 4u);
  for (auto [x, y] : {std::pair{1, 1}, {20, 3}, {21, 3}, {30, 12}}) {
    EXPECT_EQ(env.image().get(x, y), Rgb(0.0f));
    EXPECT_EQ(env.eval(texelCentre(x, y, 32, 16)), Rgb(0.0f));
    EXPECT_EQ(env.pdf(texelCentre(x, y, 32, 16)), 0.0f);
  }
  EXPECT_EQ(env.image().get(31, 12), img.get(31, 12));
  Rng rng(2);
  for (int i = 0; i < 20000; ++i) {
    EnvironmentMap::Sample s = env.sample(rng.uniform2());
    ASSERT_TRUE(std::isfinite(s.pdf) && std::isfinite(s.radiance.r) &&
                std::isfinite(s.radiance.g) && std::isfinite(s.radiance.b));
  }
  // All texels invalid: black, every one counted.
  HdrImage bad(4, 2);
  for (float& v : bad.rgb) v = NAN;
  EnvironmentMap allBad(bad);
  EXPECT_TRUE(allBad.black());
  EXPECT_EQ(allBad.invalidTexels(), 8u);
}

TEST(EnvironmentMap, ValuesBeyondHalfFloatRoundTripAndSample) {
  ScratchDir dir;
  HdrImage img(16, 8);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 16; ++x)
      img.set(x, y, Rgb(0.01f * float(x + 1), 0.5f, 1e-3f * float(y + 1)));
  img.set(5, 2, Rgb(1e6f, 2e6f, 3e6f));  // above half float's 65504
  img.set(6, 2, Rgb(70000.0f, 65505.0f, 1e30f));
  const std::string path = dir.file("bright.exr");
  writeExr(path, img);
  HdrImage back = readHdrImage(path);
  ASSERT_EQ(back.width, 16);
  ASSERT_EQ(back.height, 8);
  EXPECT_EQ(back.rgb, img.rgb);  // 32-bit float EXR: bit for bit

  // Drop the 1e30 texel (its luminance would swamp everything) and sample the 1e6 one.
  back.set(6, 2, Rgb(0.5f));
  EnvironmentMap env = EnvironmentMap::load(path);  // through load() too: same pixels
  EXPECT_EQ(env.eval(texelCentre(5, 2, 16, 8)), Rgb(1e6f, 2e6f, 3e6f));
  EnvironmentMap env2(back);
  const glm::vec3 bright = texelCentre(5, 2, 16, 8);
  // The bright texel's share of samples is its share of luminance * solid angle.
  double total = 0, mine = 0;
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 16; ++x) {
      double omega = 2 * M_PI / 16 * (rowCos(y, 8) - rowCos(y + 1, 8));
      total += luminance(back.get(x, y)) * omega;
      if (x == 5 && y == 2) mine = luminance(back.get(x, y)) * omega;
    }
  const double share = mine / total;
  // The map's pdf is a float; the reference here sums in double: 1e-5 relative covers the
  // float luminance and the rounding of the quotient.
  EXPECT_NEAR(env2.pdf(bright), luminance(back.get(5, 2)) / total, 1e-5 * env2.pdf(bright));
  Rng rng(8);
  const int n = 200000;
  int hits = 0;
  for (int i = 0; i < n; ++i) {
    EnvironmentMap::Sample s = env2.sample(rng.uniform2());
    ASSERT_TRUE(std::isfinite(s.pdf) && s.pdf > 0);
    if (s.radiance == Rgb(1e6f, 2e6f, 3e6f)) ++hits;
  }
  // 5 binomial standard deviations.
  EXPECT_NEAR(double(hits) / n, share, 5 * std::sqrt(share * (1 - share) / n));
  // And the irradiance estimate, within 5 sigma (from the texel sums) per channel.
  Rgb e = estimateIrradiance(env2, 4096, 3);
  Rgb exact = analyticIrradiance(back);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(e[k], exact[k], 5 * relativeSigmaPerSample(back, k) / 64 * exact[k]) << k;
}

TEST(HdrImage, RadianceHdrRoundTripWithinRgbePrecision) {
  ScratchDir dir;
  const int w = 37, h = 11;
  HdrImage img(w, h);
  Rng rng(6);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      // Magnitudes from 1e-3 to 1e4 and channels that differ within a pixel.
      float m = std::pow(10.0f, -3 + 7 * rng.uniform());
      img.set(x, y,
              m * Rgb(rng.uniform(), rng.uniform(), rng.uniform()) + Rgb(0.0f, 0.0f, 0.1f * m));
    }
  const std::string path = dir.file("round.hdr");
  ASSERT_NE(stbi_write_hdr(path.c_str(), w, h, 3, img.rgb.data()), 0);
  HdrImage back = readHdrImage(path);
  ASSERT_EQ(back.width, w);
  ASSERT_EQ(back.height, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      Rgb a = img.get(x, y), b = back.get(x, y);
      // RGBE stores an 8-bit mantissa per channel under the exponent of the pixel's largest
      // channel: each channel is within 2^-8 (0.4%) of that largest channel, not of itself.
      // Bound: 1% of the largest channel.
      float largest = std::max({a.r, a.g, a.b});
      for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(b[k], a[k], 0.01f * largest) << x << "," << y << " channel " << k;
    }
}

TEST(HdrImage, ErrorsNameTheFile) {
  ScratchDir dir;
  const std::string missing = dir.file("missing.exr");
  try {
    readHdrImage(missing);
    FAIL() << "no exception";
  } catch (const nestlight::Error& e) {
    EXPECT_EQ(e.file(), missing);
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos);
  }
  const std::string png = dir.file("picture.png");
  {
    std::FILE* f = std::fopen(png.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fputs("not really", f);
    std::fclose(f);
  }
  try {
    readHdrImage(png);
    FAIL() << "no exception";
  } catch (const nestlight::Error& e) {
    EXPECT_EQ(e.file(), png);
    EXPECT_NE(std::string(e.what()).find(".png"), std::string::npos);
  }
  // A truncated .hdr and a text file named .exr: errors, not crashes.
  for (const char* name : {"cut.hdr", "text.exr"}) {
    const std::string p = dir.file(name);
    {
      std::FILE* f = std::fopen(p.c_str(), "wb");
      ASSERT_NE(f, nullptr);
      std::fputs("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X", f);
      std::fclose(f);
    }
    try {
      readHdrImage(p);
      FAIL() << "no exception for " << name;
    } catch (const nestlight::Error& e) {
      EXPECT_EQ(e.file(), p);
    }
  }
  EXPECT_THROW(EnvironmentMap::load(missing), nestlight::Error);
}

TEST(HdrImage, ExrAttributesRoundTrip) {
  ScratchDir dir;
  HdrImage img(3, 2);
  img.set(2, 1, Rgb(1, 2, 3));
  ImageAttributes attrs = {
      {"nestlight:samples", "4096"}, {"nestlight:method", "reference"}, {"comment", "a b = c"}};
  const std::string path = dir.file("attrs.exr");
  writeExr(path, img, attrs);
  ImageAttributes back;
  HdrImage pixels = readHdrImage(path, &back);
  EXPECT_EQ(pixels.rgb, img.rgb);
  for (const auto& [k, v] : attrs) {
    ASSERT_TRUE(back.count(k)) << k;
    EXPECT_EQ(back.at(k), v) << k;
  }
  EXPECT_FALSE(std::filesystem::exists(path + ".partial"));
}

TEST(EnvironmentMap, RealMapsLoadAndSample) {
  struct Real {
    const char* file;
    int w, h;
    float peakLo, peakHi;  // the largest channel value we know each map to hold
  };
  const Real maps[] = {{"royal_esplanade_1k.hdr", 1024, 512, 300, 400},
                       {"stage_env_latlong.exr", 1000, 500, 4000, 4200}};
  int found = 0;
  for (const Real& m : maps) {
    const std::string path = (::nestlight::test::sharedData() / "hdr" / m.file).string();
    if (!std::filesystem::exists(path)) continue;
    ++found;
    EnvironmentMap env = EnvironmentMap::load(path, 30, 0.5f);
    EXPECT_EQ(env.image().width, m.w) << m.file;
    EXPECT_EQ(env.image().height, m.h) << m.file;
    EXPECT_FALSE(env.black()) << m.file;
    EXPECT_EQ(env.invalidTexels(), 0u) << m.file;
    float peak = 0;
    for (float v : env.image().rgb) peak = std::max(peak, v);
    EXPECT_GE(peak, m.peakLo) << m.file;
    EXPECT_LE(peak, m.peakHi) << m.file;
    Rng rng(12);
    for (int i = 0; i < 20000; ++i) {
      EnvironmentMap::Sample s = env.sample(rng.uniform2());
      ASSERT_TRUE(std::isfinite(s.pdf) && s.pdf >= 0) << m.file;
      ASSERT_TRUE(std::isfinite(s.radiance.r) && std::isfinite(s.radiance.g) &&
                  std::isfinite(s.radiance.b))
          << m.file;
      ASSERT_NEAR(glm::length(s.direction), 1, 1e-5) << m.file;  // as in SampleAgreesWithPdfAndEval
      ASSERT_EQ(s.pdf, env.pdf(s.direction));
    }
    // Irradiance estimate against the texel sums, within 5 standard deviations of the
    // estimator (computed from the texel sums) for 4096 samples.
    HdrImage scaled = env.image();
    for (float& v : scaled.rgb) v *= 0.5f;
    const Rgb exact = analyticIrradiance(scaled);
    const int n = 4096;
    Rgb e = estimateIrradiance(env, n, 5);
    for (int k = 0; k < 3; ++k) {
      double sigma = relativeSigmaPerSample(scaled, k) / std::sqrt(double(n));
      EXPECT_NEAR(e[k], exact[k], 5 * sigma * exact[k]) << m.file << " channel " << k;
      std::printf("%s channel %d: E = %.4f, texel sums %.4f, relative error %.2e (bound %.2e)\n",
                  m.file, k, e[k], exact[k], std::abs(e[k] / exact[k] - 1), 5 * sigma);
    }
  }
  if (found == 0)
    GTEST_SKIP() << "no real maps in " << ::nestlight::test::sharedData().string() << "/hdr";
}
