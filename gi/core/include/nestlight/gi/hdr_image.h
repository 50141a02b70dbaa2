// Linear HDR images: what the path tracer writes, what metrics compare and where environment
// maps come from. Three float channels per pixel, top row first, scene-referred (no tone map).
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
};

// Header attributes stored beside the pixels (e.g. "nestlight:samples" = "4096").
using ImageAttributes = std::map<std::string, std::string>;

// .exr (any pixel type; R,G,B or a single Y channel; data window honoured) or .hdr (Radiance
// RGBE). Throws nestlight::Error naming the file on unreadable or unsupported input.
HdrImage readHdrImage(const std::string& path, ImageAttributes* attributes = nullptr);
// 32-bit float RGB EXR (ZIP): full range, values above half-float's 65504 survive. Written to a
// temporary name and renamed, so a killed render leaves no file that looks complete.
void writeExr(const std::string& path, const HdrImage& image, const ImageAttributes& attributes = {});

}  // namespace nestlight::gi
