// The point view's frames: RGBA floats, top row first, display-referred (the scan's recorded sRGB
// colour), or linear (`linear`: an HDR colour layer drawn for an EXR file). Files go through gi's
// image library (nestlight/gi/hdr_image.h); EXR files get linear values, PNG display values.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace nestlight::viewer {

struct Image {
  int width = 0, height = 0;
  std::vector<float> rgba;  // 4 per pixel
  bool linear = false;      // rgb is linear (unbounded), not display-referred
  float* at(int x, int y) { return &rgba[4 * (size_t(y) * width + x)]; }
  const float* at(int x, int y) const { return &rgba[4 * (size_t(y) * width + x)]; }
};

// By extension: .png (8-bit sRGB) or .exr (half-float linear RGBA). Throws nestlight::Error.
void writeImage(const Image& img, const std::string& path);
// .png or .exr, back to display-referred floats. Throws nestlight::Error naming the file.
Image readImage(const std::string& path);

// Per-pixel comparison for image tests: a pixel differs when any channel differs by more than
// `channelTolerance` (0..1). The diff image shows differing pixels in red over a dimmed `a`.
struct ImageDiff {
  uint64_t differing = 0;
  double fraction = 0;  // differing / pixels
  double maxChannel = 0;
  double rmse = 0;  // over all pixels and RGB channels
  Image diff;
};
ImageDiff compareImages(const Image& a, const Image& b, float channelTolerance);

}  // namespace nestlight::viewer
