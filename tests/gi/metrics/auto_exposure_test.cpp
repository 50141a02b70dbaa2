// The automatic exposure of scene PNGs (gi/tone_map.h autoExposure, docs/SCENE.md "PNG exposure")
// on synthetic images whose percentile is known by construction: a sunlit plinth that 0 EV clips,
// a dim room, non-finite and black pixels that must not count, an all-black image, and the order
// in which the command line, the scene file and the automatic rule win.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>

#include "nestlight/gi/tone_map.h"

namespace nestlight::gi {
namespace {

constexpr float kNaNPixel = std::numeric_limits<float>::quiet_NaN();
constexpr float kInfPixel = std::numeric_limits<float>::infinity();

void fill(HdrImage& img, size_t from, size_t to, float r, float g, float b) {
  for (size_t p = from; p < to; ++p) {
    img.rgb[3 * p] = r, img.rgb[3 * p + 1] = g, img.rgb[3 * p + 2] = b;
  }
}

// The share of the lit pixels (finite, luminance above 0) of which some channel reaches white
// (1 after the exposure, where the sRGB curve clips).
double clippedShare(const HdrImage& img, double stops) {
  const float scale = exposureScale(stops);
  size_t lit = 0, clipped = 0;
  for (size_t p = 0; p < img.pixels(); ++p) {
    const float* c = &img.rgb[3 * p];
    if (!std::isfinite(c[0] + c[1] + c[2]) || luminance({c[0], c[1], c[2]}) <= 0) continue;
    ++lit;
    clipped += c[0] * scale >= 1 || c[1] * scale >= 1 || c[2] * scale >= 1;
  }
  return lit ? double(clipped) / double(lit) : 0.0;
}

// The albedo-mode lion: black background, a sky at 0.5, a plinth in sunlight at 3 (above white
// at 0 EV) and the sun's glints at 1000 on 0.5% of the lit pixels. The 99th percentile lies on the
// plinth, which must land at 0.8: unclipped, while the glints (fewer than 1%) may clip.
TEST(AutoExposure, SunlitPlinthIsNotClipped) {
  HdrImage img(100, 100);  // 10'000 pixels
  fill(img, 0, 4000, 0, 0, 0);
  fill(img, 4000, 7000, 0.5f, 0.5f, 0.5f);
  fill(img, 7000, 9970, 3.0f, 3.0f, 3.0f);
  fill(img, 9970, 10000, 1000.0f, 1000.0f, 1000.0f);  // 30 of 6000 lit pixels: 0.5%
  const AutoExposure a = autoExposure(img);
  EXPECT_EQ(a.pixels, 6000u);
  EXPECT_FLOAT_EQ(float(a.luminance), 3.0f);
  EXPECT_NEAR(a.stops, std::log2(0.8 / 3.0), 1e-12);
  // 0 EV clips the plinth (the defect); the automatic exposure shows it at 0.8, below white.
  EXPECT_GT(clippedShare(img, 0), 0.4);
  EXPECT_LE(clippedShare(img, a.stops), 1 - kAutoExposurePercentile);
  EXPECT_NEAR(toneMapValue(3.0f, exposureScale(a.stops)), srgbEncode(0.8f), 1e-6);
  EXPECT_LT(toneMapValue(3.0f, exposureScale(a.stops)), 0.95f);
}

// A smooth range of values (a gradient over the plinth's sides): at most 1% of the lit pixels may
// clip, whatever the spread; here none of the 99% below the percentile does.
TEST(AutoExposure, AtMostOnePercentOfALitGradientClips) {
  HdrImage img(1000, 1);
  for (size_t p = 0; p < 1000; ++p)
    fill(img, p, p + 1, 0.01f * float(p + 1), 0.01f * float(p + 1),
         0.01f * float(p + 1));  // 0.01 .. 10
  const AutoExposure a = autoExposure(img);
  EXPECT_FLOAT_EQ(float(a.luminance), 9.9f);  // nearest rank: the 990th of 1000 values
  EXPECT_LE(clippedShare(img, a.stops), 1 - kAutoExposurePercentile);
  EXPECT_GT(clippedShare(img, 0), 0.8);  // 0 EV clips the 900 values above 1
}

// A dim room (walls at luminance 0.01 to 0.05, as a Cornell box lit by a small lamp at 0 EV): the
// rule brightens it, its brightest wall to 0.8 and its darkest to a visible grey, not black.
TEST(AutoExposure, DimRoomIsBrightened) {
  HdrImage img(100, 100);
  for (size_t p = 0; p < img.pixels(); ++p) {
    const float v = 0.01f + 0.04f * float(p) / float(img.pixels() - 1);
    fill(img, p, p + 1, v * 1.2f, v, v * 0.8f);  // warm: the red channel above the luminance
  }
  const AutoExposure a = autoExposure(img);
  EXPECT_GT(a.stops, 3.9);  // 0.8 / 0.05 = 2^4 (the luminance is 1.03 v, the percentile 0.0496)
  EXPECT_LT(a.stops, 4.1);
  const float scale = exposureScale(a.stops);
  EXPECT_GT(toneMapValue(0.01f * 0.8f, scale), 0.3f);  // the darkest wall's blue channel: grey
  EXPECT_LT(clippedShare(img, a.stops), 1e-12);        // 1.2 x 0.8 / 0.99-ish: no channel clips
}

// NaN and infinite pixels and pure-black ones (the background behind a scan) do not count: the
// exposure equals that of the lit pixels alone.
TEST(AutoExposure, IgnoresNonFiniteAndBlackPixels) {
  HdrImage lit(10, 10);
  for (size_t p = 0; p < 100; ++p) fill(lit, p, p + 1, 0.02f * (p + 1), 0.02f * (p + 1), 0.02f);
  HdrImage mixed(100, 10);  // the same 100 lit pixels among 900 others
  for (size_t p = 0; p < 100; ++p)
    for (int k = 0; k < 3; ++k) mixed.rgb[3 * p + k] = lit.rgb[3 * p + k];
  fill(mixed, 100, 200, kNaNPixel, 0.5f, 0.5f);
  fill(mixed, 200, 300, kInfPixel, kInfPixel, kInfPixel);
  fill(mixed, 300, 350, 1.0f, -kInfPixel, 1.0f);
  fill(mixed, 350, 1000, 0, 0, 0);
  const AutoExposure a = autoExposure(lit), b = autoExposure(mixed);
  EXPECT_EQ(a.pixels, 100u);
  EXPECT_EQ(b.pixels, 100u);
  EXPECT_EQ(a.stops, b.stops);
  EXPECT_EQ(a.luminance, b.luminance);
  EXPECT_TRUE(std::isfinite(b.stops));
}

// Nothing lit: 0 EV, finite, however the image is empty; and a luminance so small that its
// exposure would leave the range that --exposure takes is clamped to it.
TEST(AutoExposure, BlackImageGivesZeroStops) {
  for (float v : {0.0f, kNaNPixel, kInfPixel}) {
    HdrImage img(8, 8);
    fill(img, 0, 64, v, v, v);
    const AutoExposure a = autoExposure(img);
    EXPECT_EQ(a.stops, 0.0) << v;
    EXPECT_EQ(a.pixels, 0u);
    const PngExposure e = choosePngExposure(img, std::nullopt, std::nullopt);
    EXPECT_EQ(e.stops, 0.0);
    EXPECT_NE(e.description.find("auto"), std::string::npos) << e.description;
  }
  EXPECT_EQ(autoExposure(HdrImage()).stops, 0.0);
  HdrImage faint(4, 4);
  fill(faint, 0, 16, 1e-30f, 1e-30f, 1e-30f);
  EXPECT_EQ(autoExposure(faint).stops, kExposureLimit);
}

// The command line wins over the scene file, which wins over the automatic exposure.
TEST(AutoExposure, ExplicitExposureWins) {
  HdrImage img(4, 4);
  fill(img, 0, 16, 3.0f, 3.0f, 3.0f);
  const double automatic = autoExposure(img).stops;
  ASSERT_NE(automatic, 0.0);
  const PngExposure cli = choosePngExposure(img, 1.5, -2.0);
  EXPECT_EQ(cli.stops, 1.5);
  EXPECT_NE(cli.description.find("--exposure"), std::string::npos) << cli.description;
  const PngExposure file = choosePngExposure(img, std::nullopt, -2.0);
  EXPECT_EQ(file.stops, -2.0);
  EXPECT_NE(file.description.find("output.exposure"), std::string::npos) << file.description;
  // An explicit 0 is an exposure, not "unset".
  EXPECT_EQ(choosePngExposure(img, std::nullopt, 0.0).stops, 0.0);
  EXPECT_EQ(choosePngExposure(img, 0.0, -2.0).stops, 0.0);
  const PngExposure a = choosePngExposure(img, std::nullopt, std::nullopt);
  EXPECT_EQ(a.stops, automatic);
  EXPECT_NE(a.description.find("auto"), std::string::npos) << a.description;
}

}  // namespace
}  // namespace nestlight::gi
