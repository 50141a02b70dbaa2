// Tone map and PNG output. Reference for the transfer function: IEC 61966-2-1:1999 (sRGB).
#include "nestlight/gi/tone_map.h"

#include <stb_image_write.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "nestlight/octree/error.h"

namespace nestlight::gi {

float exposureScale(double stops) {
  return float(std::exp2(stops));
}

float toneMapValue(float linear, float scale) {
  if (std::isnan(linear)) return linear;
  // The product may overflow to +Inf for huge inputs; the clamp inside srgbEncode takes it to 1.
  return srgbEncode(linear * scale);
}

HdrImage toneMap(const HdrImage& linear, double exposureStops) {
  HdrImage out(linear.width, linear.height);
  const float scale = exposureScale(exposureStops);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, linear.rgb.size(), 1 << 14), [&](const auto& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) out.rgb[i] = toneMapValue(linear.rgb[i], scale);
  });
  return out;
}

void writeToneMappedPng(const std::string& path, const HdrImage& linear, double exposureStops) {
  writePng(path, toneMap(linear, exposureStops));
}

AutoExposure autoExposure(const HdrImage& linear) {
  std::vector<float> lum;
  lum.reserve(linear.pixels());
  for (size_t p = 0; p < linear.pixels(); ++p) {
    const float* c = &linear.rgb[3 * p];
    if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2])) continue;
    const float y = luminance({c[0], c[1], c[2]});
    // Negative luminance (a negative channel, which no renderer writes) is no brightness either.
    if (y > 0 && std::isfinite(y)) lum.push_back(y);
  }
  AutoExposure a;
  a.pixels = lum.size();
  if (lum.empty()) return a;
  // Nearest rank: the smallest value with at least the percentile of the counted pixels at or
  // below it, so at most (1 - percentile) of them lie above it.
  // (The guard keeps 0.99 * 1000, a hair above 990 in binary, from rounding up a rank.)
  const size_t rank =
      size_t(std::max(1.0, std::ceil(kAutoExposurePercentile * double(lum.size()) - 1e-9))) - 1;
  auto at = lum.begin() + std::ptrdiff_t(std::min(rank, lum.size() - 1));
  std::nth_element(lum.begin(), at, lum.end());
  a.luminance = *at;
  a.stops =
      std::clamp(std::log2(kAutoExposureWhite / a.luminance), -kExposureLimit, kExposureLimit);
  return a;
}

PngExposure choosePngExposure(const HdrImage& linear, std::optional<double> commandLine,
                              std::optional<double> sceneFile) {
  PngExposure e;
  char buf[160];
  if (commandLine || sceneFile) {
    e.stops = commandLine ? *commandLine : *sceneFile;
    std::snprintf(buf, sizeof buf, "%+.2f EV (%s)", e.stops,
                  commandLine ? "--exposure" : "the scene's output.exposure");
  } else {
    const AutoExposure a = autoExposure(linear);
    e.stops = a.stops;
    if (a.pixels == 0)
      std::snprintf(buf, sizeof buf, "%+.2f EV (auto: no pixel above black)", e.stops);
    else
      std::snprintf(buf, sizeof buf,
                    "%+.2f EV (auto: the lit pixels' %gth luminance percentile, %.3g, put at %g)",
                    e.stops, 100 * kAutoExposurePercentile, a.luminance, kAutoExposureWhite);
  }
  e.description = buf;
  return e;
}

}  // namespace nestlight::gi
