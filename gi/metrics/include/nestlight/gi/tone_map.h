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

}  // namespace nestlight::gi
