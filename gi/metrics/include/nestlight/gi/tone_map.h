// The one tone map of Nestlight: what a render writes as PNG and what the "tone-mapped" error
// metrics measure are the same pixels, so a metric never judges an image nobody looks at.
//
// Curve: multiply by 2^exposureStops, clamp to [0, 1], then apply the sRGB opto-electronic
// transfer function of IEC 61966-2-1:1999 (linear toe of slope 12.92 below 0.0031308, a 1/2.4
// power above). Chosen over a filmic curve (e.g. Narkowicz's ACES fit) because it is the exact
// inverse of how the scan's 8-bit sRGB colours were decoded, so a lit scan that reproduces its
// recorded colour tone-maps back to that colour; highlights above 1 clip here, and the linear
// HDR metrics are the ones that still see them.
#pragma once

#include <optional>
#include <string>

#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/srgb.h"  // srgbEncode, srgbDecode

namespace nestlight::gi {

// 2^stops as a float multiplier.
float exposureScale(double stops);

// One channel through the curve with a precomputed exposureScale. NaN stays NaN so that callers
// can see it; +Inf clips to 1 and -Inf to 0, as any value beyond the range does.
float toneMapValue(float linear, float scale);

// Display-referred image (values in [0, 1] or NaN) of a linear one.
HdrImage toneMap(const HdrImage& linear, double exposureStops);

// toneMap then writePng: what renders write beside their EXR.
void writeToneMappedPng(const std::string& path, const HdrImage& linear, double exposureStops);

// Automatic exposure of scene PNGs (docs/SCENE.md, "PNG exposure"): the stops that put the
// kAutoExposurePercentile of the image's luminance (Rec. 709 weights) at kAutoExposureWhite, just
// below white. Only finite pixels with luminance above 0 count: NaN and infinite pixels are no
// brightness, and a scan or object seen against a black background must not be exposed for the
// background. The 99th percentile keeps the brightest 1% of those pixels free to clip (a visible
// lamp, the sun's specular highlight) while everything lit, a sunlit plinth included, stays below
// white; aimed at 0.8 linear (sRGB 0.91, 8-bit 231) rather than 1, a warm or coloured pixel of that
// luminance keeps its largest channel unclipped up to 1.25 times its luminance. A dim room is
// brightened by the same rule (its brightest walls land at 0.8). No counted pixel (all black, all
// non-finite): 0 stops. The result is clamped to the range --exposure and output.exposure accept.
inline constexpr double kAutoExposurePercentile = 0.99;
inline constexpr double kAutoExposureWhite = 0.8;
inline constexpr double kExposureLimit = 64;  // |stops| that --exposure and output.exposure take

struct AutoExposure {
  double stops = 0;
  double luminance = 0;  // the percentile's luminance (0 when no pixel counted)
  size_t pixels = 0;     // the finite pixels with luminance above 0 that were counted
};
AutoExposure autoExposure(const HdrImage& linear);

// The exposure a scene's PNG is written with: the command line's if given, else the scene file's
// output.exposure, else autoExposure of `linear`. `description` says which and why, for the log
// ("+1.30 EV (auto: the lit pixels' 99th luminance percentile, 0.325, put at 0.8)").
struct PngExposure {
  double stops = 0;
  std::string description;
};
PngExposure choosePngExposure(const HdrImage& linear, std::optional<double> commandLine,
                              std::optional<double> sceneFile);

}  // namespace nestlight::gi
