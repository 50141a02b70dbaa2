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

}  // namespace nestlight::gi
