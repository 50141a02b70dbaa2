#include "nestlight/viewer/image.h"

#include <ImfArray.h>
#include <ImfRgbaFile.h>
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "nestlight/octree/error.h"

namespace nestlight::viewer {

namespace {
std::string extensionOf(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e;
}
}  // namespace

float srgbToLinear(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}
float linearToSrgb(float v) {
  return v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1.f / 2.4f) - 0.055f;
}

void writeImage(const Image& img, const std::string& path) {
  const std::string ext = extensionOf(path);
  if (img.width <= 0 || img.height <= 0) throw Error(path, "", "cannot write an empty image");
  if (ext == ".png") {
    std::vector<uint8_t> px(size_t(img.width) * img.height * 4);
    for (size_t i = 0; i < px.size(); ++i)
      px[i] = static_cast<uint8_t>(std::lround(std::clamp(img.rgba[i], 0.f, 1.f) * 255.f));
    if (!stbi_write_png(path.c_str(), img.width, img.height, 4, px.data(), img.width * 4))
      throw Error(path, "", "cannot write PNG");
  } else if (ext == ".exr") {
    try {
      std::vector<Imf::Rgba> px(size_t(img.width) * img.height);
      for (size_t i = 0; i < px.size(); ++i)
        px[i] = Imf::Rgba(srgbToLinear(img.rgba[4 * i]), srgbToLinear(img.rgba[4 * i + 1]),
                          srgbToLinear(img.rgba[4 * i + 2]), img.rgba[4 * i + 3]);
      Imf::RgbaOutputFile out(path.c_str(), img.width, img.height, Imf::WRITE_RGBA);
      out.setFrameBuffer(px.data(), 1, img.width);
      out.writePixels(img.height);
    } catch (const std::exception& e) {
      throw Error(path, "", std::string("cannot write EXR: ") + e.what());
    }
  } else {
    throw Error(path, "", "unknown image type '" + ext + "' (use .png or .exr)");
  }
}

Image readImage(const std::string& path) {
  const std::string ext = extensionOf(path);
  Image img;
  if (ext == ".png") {
    int w = 0, h = 0, n = 0;
    uint8_t* data = stbi_load(path.c_str(), &w, &h, &n, 4);
    if (!data) throw Error(path, "", std::string("cannot read PNG: ") + stbi_failure_reason());
    img.width = w, img.height = h;
    img.rgba.resize(size_t(w) * h * 4);
    for (size_t i = 0; i < img.rgba.size(); ++i) img.rgba[i] = data[i] / 255.f;
    stbi_image_free(data);
  } else if (ext == ".exr") {
    try {
      Imf::RgbaInputFile in(path.c_str());
      const Imath::Box2i dw = in.dataWindow();
      img.width = dw.max.x - dw.min.x + 1, img.height = dw.max.y - dw.min.y + 1;
      std::vector<Imf::Rgba> px(size_t(img.width) * img.height);
      in.setFrameBuffer(px.data() - dw.min.x - size_t(dw.min.y) * img.width, 1, img.width);
      in.readPixels(dw.min.y, dw.max.y);
      img.rgba.resize(px.size() * 4);
      for (size_t i = 0; i < px.size(); ++i) {
        img.rgba[4 * i] = linearToSrgb(px[i].r);
        img.rgba[4 * i + 1] = linearToSrgb(px[i].g);
        img.rgba[4 * i + 2] = linearToSrgb(px[i].b);
        img.rgba[4 * i + 3] = px[i].a;
      }
    } catch (const std::exception& e) {
      throw Error(path, "", std::string("cannot read EXR: ") + e.what());
    }
  } else {
    throw Error(path, "", "unknown image type '" + ext + "' (use .png or .exr)");
  }
  return img;
}

ImageDiff compareImages(const Image& a, const Image& b, float tol) {
  if (a.width != b.width || a.height != b.height)
    throw Error("images differ in size: " + std::to_string(a.width) + "x" + std::to_string(a.height) + " and " +
                std::to_string(b.width) + "x" + std::to_string(b.height));
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
