// Generalized PatchMatch (Barnes, Shechtman, Goldman and Finkelstein, "The Generalized PatchMatch
// Correspondence Algorithm", ECCV 2010) as HDR expansion uses it (Sabbadin, Palma, Banterle,
// Boubekeur and Cignoni, "High Dynamic Range Point Clouds for Real-Time Relighting", 2019,
// section 4.1): identity, known rotations and scales recovered, masks, determinism, fetching HDR
// values at the matches.
#include "nestlight/gi/hdr/patchmatch.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ostream>

#include "nestlight/octree/error.h"

namespace nestlight::gi::hdr {
namespace {

constexpr float kPiF = 3.14159265358979f;

uint64_t hash(uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// A lattice value in [-1, 1] per integer point and channel, from a hash: no period anywhere.
float lattice(int64_t i, int64_t j, int channel, uint64_t seed) {
  const uint64_t h =
      hash(seed ^ hash(uint64_t(i) * 0x1f1f1f1fULL ^ hash(uint64_t(j) * 3 + channel)));
  return float(h >> 40) * 0x1p-23f - 1.0f;
}

float bspline(float t) {  // the uniform cubic B-spline, support [-2, 2]
  t = std::abs(t);
  if (t < 1) return (4 - 6 * t * t + 3 * t * t * t) / 6;
  if (t < 2) return (2 - t) * (2 - t) * (2 - t) / 6;
  return 0;
}

// Smooth colour noise defined everywhere on the plane (so resampled images are exact, not
// interpolated): two octaves of B-spline-interpolated random lattices, 8 and 4 pixels apart. The
// B-spline is a convex combination, so values stay in [0.05, 0.95]: display-referred, never
// clamped.
Rgb texture(float x, float y, uint64_t seed) {
  Rgb c(0.5f);
  const float spacing[2] = {8.0f, 4.0f}, amplitude[2] = {0.3f, 0.15f};
  for (int o = 0; o < 2; ++o) {
    const float u = x / spacing[o], v = y / spacing[o];
    const int64_t i0 = int64_t(std::floor(u)), j0 = int64_t(std::floor(v));
    for (int64_t j = j0 - 1; j <= j0 + 2; ++j)
      for (int64_t i = i0 - 1; i <= i0 + 2; ++i) {
        const float wgt = amplitude[o] * bspline(u - float(i)) * bspline(v - float(j));
        for (int ch = 0; ch < 3; ++ch) c[ch] += wgt * lattice(i, j, ch, seed + uint64_t(o));
      }
  }
  return c;
}

HdrImage textureImage(int w, int h, uint64_t seed) {
  HdrImage img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.set(x, y, texture(float(x), float(y), seed));
  return img;
}

// The true match of a source pixel when source(p) = target(tc + scale R(angle) (p - sc)).
struct Similarity {
  glm::vec2 sourceCentre, targetCentre;
  float angle, scale;
  glm::vec2 operator()(glm::vec2 p) const {
    const glm::vec2 d = p - sourceCentre;
    const float c = std::cos(angle), s = std::sin(angle);
    return targetCentre + scale * glm::vec2(c * d.x - s * d.y, s * d.x + c * d.y);
  }
};

HdrImage resampled(int w, int h, const Similarity& m, uint64_t seed) {
  HdrImage img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const glm::vec2 q = m(glm::vec2(x, y));
      img.set(x, y, texture(q.x, q.y, seed));
    }
  return img;
}

float angleDifference(float a, float b) {
  float d = std::fmod(a - b, 2 * kPiF);
  if (d > kPiF) d -= 2 * kPiF;
  if (d < -kPiF) d += 2 * kPiF;
  return std::abs(d);
}

float median(std::vector<float> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

TEST(PatchMatch, MatchesAnImageToItself) {
  const HdrImage image = textureImage(96, 96, 11);
  const PatchMatchField f = generalizedPatchMatch(image, image);
  ASSERT_EQ(f.position.size(), image.pixels());
  size_t placed = 0;
  std::vector<float> ssd, angle, scale;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const size_t i = f.index(x, y);
      placed += glm::length(f.position[i] - glm::vec2(x, y)) <= 0.5f;
      ssd.push_back(f.ssd[i]);
      angle.push_back(std::abs(f.angle[i]) * 180 / kPiF);
      scale.push_back(std::abs(f.scale[i] - 1));
    }
  const float placedFraction = float(placed) / float(image.pixels());
  const float medianSsd = median(ssd), maxSsd = *std::max_element(ssd.begin(), ssd.end());
  std::printf(
      "identity: %.4f within 0.5 px, median ssd %.2g, max %.2g, median |angle| %.3f deg, "
      "|scale - 1| %.3f%%\n",
      placedFraction, medianSsd, maxSsd, median(angle), 100 * median(scale));
  // Random search is continuous, so a match is near the identity (a fraction of a pixel and of a
  // degree), not at it; 99% leaves room for a few pixels stuck in a nearby self-similar spot.
  EXPECT_GE(placedFraction, 0.99f);
  EXPECT_LT(median(angle), 1.0f);
  EXPECT_LT(median(scale), 0.01f);
  // 147 terms: a median under 1e-4 is an RMS difference under 0.001 (a quarter of an 8-bit step),
  // four orders of magnitude under the paper's rejection threshold of 1.
  EXPECT_LT(medianSsd, 1e-4f);
  EXPECT_LT(maxSsd, 1.0f);  // nothing an HDR expansion would reject
}

struct KnownTransform {
  float angleDegrees, scale;
};

void PrintTo(const KnownTransform& t, std::ostream* os) {
  *os << t.angleDegrees << " degrees, scale " << t.scale;
}

class PatchMatchKnownTransform : public ::testing::TestWithParam<KnownTransform> {};

// The photograph sees the rendering rotated and scaled about the centre (by more than 90 degrees
// too, scaled up and down). For source pixels whose patch lies well inside both
// images the field should recover the mapping: positions within 1 px (further off, a match sits
// on other texels) for 95% of them; median angle within 1 degree and median scale within 2%.
// Either error moves a 7x7 patch's corner samples by about a tenth of a target pixel, where the
// target's bilinear interpolation (a slight blur, which biases scales under 1 by up to 0.9%)
// flattens the SSD's minimum. Measured over 8 seeds each of 7 transforms: every interior pixel
// within 1 px, medians under 0.3 degrees and 0.9%.
TEST_P(PatchMatchKnownTransform, RecoversRotationAndScale) {
  const KnownTransform truth = GetParam();
  const int size = 128;
  const uint64_t seed = 5;
  const Similarity m{glm::vec2(size / 2), glm::vec2(size / 2), truth.angleDegrees * kPiF / 180,
                     truth.scale};
  const HdrImage target = textureImage(size, size, seed);
  const HdrImage source = resampled(size, size, m, seed);
  const PatchMatchField f = generalizedPatchMatch(source, target);

  const int r = PatchMatchOptions{}.patchRadius;
  const float margin = float(r) * truth.scale * std::sqrt(2.0f) + 2;
  size_t interior = 0, placed = 0;
  std::vector<float> angleError, scaleError;
  for (int y = r; y < size - r; ++y)
    for (int x = r; x < size - r; ++x) {
      const glm::vec2 q = m(glm::vec2(x, y));
      if (q.x < margin || q.y < margin || q.x > size - 1 - margin || q.y > size - 1 - margin)
        continue;
      const size_t i = f.index(x, y);
      interior++;
      placed += glm::length(f.position[i] - q) <= 1.0f;
      angleError.push_back(angleDifference(f.angle[i], m.angle) * 180 / kPiF);
      scaleError.push_back(std::abs(f.scale[i] / truth.scale - 1));
    }
  ASSERT_GT(interior, 2000u);
  const float placedFraction = float(placed) / float(interior);
  std::printf(
      "%g deg, scale %g: %zu interior pixels, %.4f within 1 px, median angle error %.3f "
      "deg, median scale error %.3f%%\n",
      truth.angleDegrees, truth.scale, interior, placedFraction, median(angleError),
      100 * median(scaleError));
  EXPECT_GE(placedFraction, 0.95f);
  EXPECT_LT(median(angleError), 1.0f);
  EXPECT_LT(median(scaleError), 0.02f);
}

INSTANTIATE_TEST_SUITE_P(Transforms, PatchMatchKnownTransform,
                         ::testing::Values(KnownTransform{30, 1.4f}, KnownTransform{120, 0.75f},
                                           KnownTransform{-150, 1.8f}));

TEST(PatchMatch, MaskedPixelsAreSkipped) {
  const HdrImage image = textureImage(96, 80, 3);
  std::vector<uint8_t> mask(image.pixels(), 0);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) mask[size_t(y) * image.width + x] = (x / 8 + y / 8) % 2;
  const PatchMatchField f = generalizedPatchMatch(image, image, {}, &mask);
  size_t matched = 0, placed = 0;
  for (size_t i = 0; i < image.pixels(); ++i) {
    if (!mask[i]) {
      EXPECT_EQ(f.ssd[i], std::numeric_limits<float>::infinity()) << i;
      EXPECT_EQ(f.position[i], glm::vec2(-1.0f)) << i;
      continue;
    }
    matched++;
    const glm::vec2 p(float(i % image.width), float(i / image.width));
    placed += std::isfinite(f.ssd[i]) && glm::length(f.position[i] - p) <= 0.5f;
  }
  // Masked-out pixels still lend their colours to their neighbours' patches and the matched
  // checker squares find themselves as in the unmasked identity test.
  EXPECT_GE(float(placed) / float(matched), 0.99f);

  const std::vector<uint8_t> none(image.pixels(), 0);
  const PatchMatchField empty = generalizedPatchMatch(image, image, {}, &none);
  EXPECT_TRUE(
      std::all_of(empty.ssd.begin(), empty.ssd.end(), [](float v) { return std::isinf(v); }));

  const std::vector<uint8_t> wrong(10, 1);
  EXPECT_THROW(generalizedPatchMatch(image, image, {}, &wrong), Error);
}

TEST(PatchMatch, SameSeedSameFieldWhateverTheThreads) {
  const Similarity m{glm::vec2(40), glm::vec2(48), 0.7f, 1.2f};
  const HdrImage target = textureImage(96, 96, 9), source = resampled(80, 80, m, 9);
  PatchMatchOptions options;
  options.seed = 42;
  const PatchMatchField a = generalizedPatchMatch(source, target, options);
  PatchMatchField b;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    b = generalizedPatchMatch(source, target, options);
  }
  EXPECT_EQ(a.position, b.position);
  EXPECT_EQ(a.angle, b.angle);
  EXPECT_EQ(a.scale, b.scale);
  EXPECT_EQ(a.ssd, b.ssd);
  options.seed = 43;
  const PatchMatchField c = generalizedPatchMatch(source, target, options);
  EXPECT_NE(a.angle, c.angle);  // the seed is used
}

TEST(PatchMatch, FetchIsBilinearAtThePositions) {
  HdrImage image(3, 2);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x) image.set(x, y, Rgb(float(x), float(10 * y), float(x + 10 * y)));
  PatchMatchField f;
  f.width = 2, f.height = 1, f.targetWidth = 3, f.targetHeight = 2;
  f.position = {glm::vec2(1.25f, 0.5f), glm::vec2(1, 1)};
  f.angle = {0, 0}, f.scale = {1, 1};
  f.ssd = {0.5f, std::numeric_limits<float>::infinity()};
  const HdrImage out = fetch(f, image);
  EXPECT_EQ(out.get(0, 0), Rgb(1.25f, 5.0f, 6.25f));
  EXPECT_EQ(out.get(1, 0), Rgb(0.0f));  // masked out
  EXPECT_THROW(fetch(f, HdrImage(2, 2)), Error);
}

// The paper's use: match the rendering against the LDR photograph, read the HDR photograph (here
// 10 times the LDR one on its right half, where the LDR one would have clipped) at the matches.
TEST(PatchMatch, FetchReadsTheHdrPhotographAtTheMatches) {
  const int w = 112, h = 96;
  const HdrImage ldr = textureImage(w, h, 21);
  HdrImage hdr = ldr;
  for (int y = 0; y < h; ++y)
    for (int x = w / 2; x < w; ++x) hdr.set(x, y, 10.0f * ldr.get(x, y));
  // The rendering: the photograph's middle, shifted by (13, 7).
  const Similarity m{glm::vec2(0), glm::vec2(13, 7), 0, 1};
  const HdrImage source = resampled(w - 26, h - 14, m, 21);
  const PatchMatchField f = generalizedPatchMatch(source, ldr);
  const HdrImage fetched = fetch(f, hdr);
  ASSERT_EQ(fetched.width, source.width);
  size_t bright = 0, dark = 0;
  float worst = 0, worstPosition = 0;
  for (int y = 0; y < source.height; ++y)
    for (int x = 0; x < source.width; ++x) {
      const size_t i = f.index(x, y);
      const glm::vec2 truth = m(glm::vec2(x, y));
      if (std::abs(truth.x - float(w / 2)) < 2) continue;  // bilinear straddles the step
      const float gain = truth.x > float(w / 2) ? 10.0f : 1.0f;
      const Rgb error = glm::abs(fetched.get(x, y) - gain * source.get(x, y)) / gain;
      worst = std::max({worst, error.r, error.g, error.b});
      (gain > 1 ? bright : dark)++;
      worstPosition = std::max(worstPosition, glm::length(f.position[i] - truth));
      EXPECT_LT(f.ssd[i], 1.0f);
    }
  std::printf("fetch: positions within %.3f px, values within %.4f of the gain\n", worstPosition,
              worst);
  EXPECT_GT(bright, 2000u);
  EXPECT_GT(dark, 2000u);
  // A translation is the easiest match: every position within 0.1 px. The texture changes by at
  // most 0.07 per pixel along either axis, so such a position reads within 0.014 (times the gain)
  // of the truth; a region read at the wrong gain would be off by 9 times its value (over 0.4).
  EXPECT_LT(worstPosition, 0.1f);
  EXPECT_LT(worst, 0.015f);
}

}  // namespace
}  // namespace nestlight::gi::hdr
