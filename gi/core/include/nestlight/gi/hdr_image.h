// The image library of Nestlight: linear HDR images (what every GI method writes, what metrics
// compare, where environment maps come from) and their files, EXR and Radiance HDR, plus 8-bit
// PNG for display-referred pixels (tone-mapped renders, the point view's frames, goldens). Three
// float channels per pixel, top row first. The sRGB transfer functions are in srgb.h, the tone
// map and the error metrics in gi/metrics; the point view's RGBA frames convert to and from
// these (nestlight/viewer/image.h).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "nestlight/gi/sampling.h"

namespace nestlight::gi {

struct HdrImage {
  int width = 0, height = 0;
  std::vector<float> rgb;  // 3 per pixel

  HdrImage() = default;
  HdrImage(int w, int h) : width(w), height(h), rgb(size_t(w) * h * 3, 0.0f) {}
  size_t pixels() const { return size_t(width) * height; }
  Rgb get(int x, int y) const {
    const float* p = &rgb[3 * (size_t(y) * width + x)];
    return {p[0], p[1], p[2]};
  }
  void set(int x, int y, const Rgb& c) {
    float* p = &rgb[3 * (size_t(y) * width + x)];
    p[0] = c.r, p[1] = c.g, p[2] = c.b;
  }
  // The pixels as RGBA (alpha 1), the layout GL uploads take.
  std::vector<float> rgba() const {
    std::vector<float> out(pixels() * 4, 1.0f);
    for (size_t p = 0; p < pixels(); ++p)
      for (int k = 0; k < 3; ++k) out[4 * p + k] = rgb[3 * p + k];
    return out;
  }
};

// Header attributes stored beside the pixels (e.g. "nestlight:samples" = "4096").
using ImageAttributes = std::map<std::string, std::string>;

// .exr (any pixel type; R,G,B or a single Y channel; data window honoured) or .hdr (Radiance
// RGBE). Throws nestlight::Error naming the file on unreadable or unsupported input.
HdrImage readHdrImage(const std::string& path, ImageAttributes* attributes = nullptr);
// 32-bit float RGB EXR (ZIP): full range, values above half-float's 65504 survive. Written to a
// temporary name and renamed, so a killed render leaves no file that looks complete.
void writeExr(const std::string& path, const HdrImage& image,
              const ImageAttributes& attributes = {});

// 8-bit RGB PNG of display-referred values in [0, 1] (clamped), rounded to nearest. A pixel with a
// NaN channel is written magenta (255, 0, 255) so that it shows instead of turning silently
// black. Written to a temporary name and renamed. Throws nestlight::Error naming `path`.
void writePng(const std::string& path, const HdrImage& display);
// A PNG (8 or 16 bits, grey or colour, alpha dropped) as display-referred values in [0, 1].
HdrImage readPng(const std::string& path);

}  // namespace nestlight::gi
