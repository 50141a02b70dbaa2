// sRGB transfer function, IEC 61966-2-1:1999 (linear toe below 0.0031308 / 0.04045, 2.4 power
// above).
#include "nestlight/gi/srgb.h"

#include <algorithm>
#include <cmath>

namespace nestlight::gi {

float srgbEncode(float linear) {
  float v = std::clamp(linear, 0.0f, 1.0f);
  if (v == 1.0f) return 1.0f;  // 1.055f - 0.055f rounds below 1: white must stay white
  return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

float srgbDecode(float encoded) {
  float v = std::clamp(encoded, 0.0f, 1.0f);
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

}  // namespace nestlight::gi
