// The point view's frames as files (the frame itself, frame::Image, is the point view's:
// nestlight/frame/image.h). Files go through gi's image library (nestlight/gi/hdr_image.h); EXR
// files get linear values, PNG display values.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "nestlight/frame/image.h"

namespace nestlight::viewer {

using frame::Image;

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
