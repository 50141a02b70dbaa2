#include "nestlight/viewer/image.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/srgb.h"
#include "nestlight/octree/error.h"

namespace nestlight::viewer {

namespace {
std::string extensionOf(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e;
}
}  // namespace

// The files are gi's (nestlight/gi/hdr_image.h): one EXR, PNG and sRGB implementation for the
// whole program. EXR files hold linear values, PNG files display values: whichever of the two the
// image is not, it is converted by the sRGB curve (PNG clamps linear values above 1).
void writeImage(const Image& img, const std::string& path) {
  const std::string ext = extensionOf(path);
  if (img.width <= 0 || img.height <= 0) throw Error(path, "", "cannot write an empty image");
  if (ext != ".png" && ext != ".exr")
    throw Error(path, "", "unknown image type '" + ext + "' (use .png or .exr)");
  gi::HdrImage out(img.width, img.height);
  for (size_t p = 0; p < out.pixels(); ++p)
    for (int k = 0; k < 3; ++k) {
      const float v = img.rgba[4 * p + k];
      if (ext == ".exr")
        out.rgb[3 * p + k] = img.linear ? v : gi::srgbDecode(v);
      else
        out.rgb[3 * p + k] = img.linear ? gi::srgbEncode(v) : v;
    }
  if (ext == ".png")
    gi::writePng(path, out);
  else
    gi::writeExr(
        path, out,
        {{"nestlight:content", img.linear ? "point view, linear colour (HDR colour layer)"
                                          : "point view, linear from display-referred sRGB"}});
}

Image readImage(const std::string& path) {
  const std::string ext = extensionOf(path);
  if (ext != ".png" && ext != ".exr")
    throw Error(path, "", "unknown image type '" + ext + "' (use .png or .exr)");
  const gi::HdrImage in = ext == ".png" ? gi::readPng(path) : gi::readHdrImage(path);
  Image img;
  img.width = in.width, img.height = in.height;
  img.rgba.assign(in.pixels() * 4, 1.0f);
  for (size_t p = 0; p < in.pixels(); ++p)
    for (int k = 0; k < 3; ++k) {
      const float v = in.rgb[3 * p + k];
      img.rgba[4 * p + k] = ext == ".exr" ? gi::srgbEncode(v) : v;
    }
  return img;
}

ImageDiff compareImages(const Image& a, const Image& b, float tol) {
  if (a.width != b.width || a.height != b.height)
    throw Error("images differ in size: " + std::to_string(a.width) + "x" +
                std::to_string(a.height) + " and " + std::to_string(b.width) + "x" +
                std::to_string(b.height));
  ImageDiff d;
  d.diff = a;
  double sq = 0;
  const size_t n = size_t(a.width) * a.height;
  for (size_t i = 0; i < n; ++i) {
    double worst = 0;
    for (int c = 0; c < 3; ++c) {
      const double e = std::fabs(double(a.rgba[4 * i + c]) - b.rgba[4 * i + c]);
      worst = std::max(worst, e);
      sq += e * e;
    }
    d.maxChannel = std::max(d.maxChannel, worst);
    float* o = &d.diff.rgba[4 * i];
    if (worst > tol) {
      ++d.differing;
      o[0] = 1, o[1] = 0, o[2] = 0;
    } else {
      for (int c = 0; c < 3; ++c) o[c] *= 0.3f;
    }
    o[3] = 1;
  }
  d.fraction = n ? double(d.differing) / n : 0;
  d.rmse = n ? std::sqrt(sq / (3.0 * n)) : 0;
  return d;
}

}  // namespace nestlight::viewer
