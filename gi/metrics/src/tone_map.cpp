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

void writePng(const std::string& path, const HdrImage& display) {
  if (display.width <= 0 || display.height <= 0 || display.rgb.size() != display.pixels() * 3)
    throw Error(path, "", "cannot write an empty image as PNG");
  std::vector<uint8_t> bytes(display.rgb.size());
  for (size_t p = 0; p < display.pixels(); ++p) {
    const float* c = &display.rgb[3 * p];
    if (std::isnan(c[0]) || std::isnan(c[1]) || std::isnan(c[2])) {
      bytes[3 * p] = 255, bytes[3 * p + 1] = 0, bytes[3 * p + 2] = 255;
      continue;
    }
    for (int k = 0; k < 3; ++k)
      bytes[3 * p + k] = uint8_t(std::lround(std::clamp(c[k], 0.0f, 1.0f) * 255.0f));
  }
  const std::string tmp = path + ".partial";
  if (!stbi_write_png(tmp.c_str(), display.width, display.height, 3, bytes.data(),
                      display.width * 3)) {
    std::remove(tmp.c_str());
    throw Error(path, "", "cannot write PNG");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw Error(path, "", "cannot rename " + tmp + ": " + ec.message());
  }
}

void writeToneMappedPng(const std::string& path, const HdrImage& linear, double exposureStops) {
  writePng(path, toneMap(linear, exposureStops));
}

}  // namespace nestlight::gi
