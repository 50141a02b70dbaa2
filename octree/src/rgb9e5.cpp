#include "nestlight/octree/rgb9e5.h"

#include <algorithm>
#include <cmath>

namespace nestlight {

namespace {
constexpr int kMantissaBits = 9, kBias = 15;
}

// The encoding of EXT_texture_shared_exponent (section "RGB9E5 encoding"): the shared exponent
// from the largest channel, bumped when rounding would overflow its mantissa.
uint32_t packRgb9e5(float r, float g, float b) {
  float rgb[3] = {r, g, b};
  for (float& c : rgb) c = std::isfinite(c) ? std::clamp(c, 0.0f, kRgb9e5Max) : 0.0f;
  const float maxc = std::max({rgb[0], rgb[1], rgb[2]});
  int exp = std::max(-kBias - 1, int(std::floor(std::log2(std::max(maxc, 1e-30f))))) + 1 + kBias;
  double denom = std::ldexp(1.0, exp - kBias - kMantissaBits);
  if (int(std::floor(maxc / denom + 0.5)) == (1 << kMantissaBits)) {
    exp++;
    denom *= 2;
  }
  uint32_t out = uint32_t(exp) << 27;
  for (int c = 0; c < 3; ++c)
    out |= uint32_t(std::min<double>(std::floor(rgb[c] / denom + 0.5), (1 << kMantissaBits) - 1))
           << (9 * c);
  return out;
}

void unpackRgb9e5(uint32_t v, float rgb[3]) {
  const double scale = std::ldexp(1.0, int(v >> 27) - kBias - kMantissaBits);
  for (int c = 0; c < 3; ++c) rgb[c] = float((v >> (9 * c) & 511) * scale);
}

}  // namespace nestlight
