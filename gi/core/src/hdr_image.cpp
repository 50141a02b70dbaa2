#include "nestlight/gi/hdr_image.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStandardAttributes.h>
#include <ImfStringAttribute.h>
#include <stb_image.h>
#include <stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "nestlight/octree/error.h"

namespace nestlight::gi {
namespace {

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

HdrImage readExr(const std::string& path, ImageAttributes* attributes) {
  try {
    Imf::InputFile in(path.c_str());
    const Imf::Header& h = in.header();
    Imath::Box2i dw = h.dataWindow();
    int64_t w64 = int64_t(dw.max.x) - dw.min.x + 1, h64 = int64_t(dw.max.y) - dw.min.y + 1;
    if (w64 <= 0 || h64 <= 0 || w64 * h64 > (int64_t(1) << 31))
      throw Error(path, "header",
                  "data window of " + std::to_string(w64) + "x" + std::to_string(h64) +
                      " pixels is empty or too large");
    HdrImage img{int(w64), int(h64)};
    const Imf::ChannelList& ch = h.channels();
    bool rgb = ch.findChannel("R") && ch.findChannel("G") && ch.findChannel("B");
    bool y = ch.findChannel("Y");
    if (!rgb && !y) throw Error(path, "header", "no R,G,B or Y channels");
    Imf::FrameBuffer fb;
    // OpenEXR addresses pixels by absolute coordinates; shift the base so (min.x, min.y) is 0.
    char* base = reinterpret_cast<char*>(img.rgb.data()) -
                 (int64_t(dw.min.x) + int64_t(dw.min.y) * img.width) * int64_t(3 * sizeof(float));
    size_t xs = 3 * sizeof(float), ys = xs * img.width;
    if (rgb) {
      fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
      fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
      fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
    } else {
      fb.insert("Y", Imf::Slice(Imf::FLOAT, base, xs, ys));
    }
    in.setFrameBuffer(fb);
    in.readPixels(dw.min.y, dw.max.y);
    if (!rgb)
      for (size_t i = 0; i < img.pixels(); ++i)
        img.rgb[3 * i + 1] = img.rgb[3 * i + 2] = img.rgb[3 * i];
    if (attributes) {
      for (auto it = h.begin(); it != h.end(); ++it)
        if (auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute()))
          (*attributes)[it.name()] = s->value();
    }
    return img;
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(path, "", std::string("cannot read EXR: ") + e.what());
  }
}

HdrImage readRadianceHdr(const std::string& path) {
  int w = 0, h = 0, n = 0;
  float* data = stbi_loadf(path.c_str(), &w, &h, &n, 3);
  if (!data)
    throw Error(path, "", std::string("cannot read Radiance HDR: ") + stbi_failure_reason());
  HdrImage img(w, h);
  std::copy(data, data + img.rgb.size(), img.rgb.begin());
  stbi_image_free(data);
  return img;
}

}  // namespace

HdrImage readHdrImage(const std::string& path, ImageAttributes* attributes) {
  if (!std::filesystem::exists(path)) throw Error(path, "", "no such file");
  std::string ext = lowerExtension(path);
  if (ext == ".exr") return readExr(path, attributes);
  if (ext == ".hdr" || ext == ".pic") return readRadianceHdr(path);
  throw Error(path, "", "unsupported HDR image type '" + ext + "' (expected .exr or .hdr)");
}

void writeExr(const std::string& path, const HdrImage& image, const ImageAttributes& attributes) {
  NL_CHECK(image.width > 0 && image.height > 0 && image.rgb.size() == image.pixels() * 3);
  std::string tmp = path + ".partial";
  try {
    Imf::Header h(image.width, image.height);
    h.compression() = Imf::ZIP_COMPRESSION;
    for (const char* c : {"R", "G", "B"}) h.channels().insert(c, Imf::Channel(Imf::FLOAT));
    for (const auto& [k, v] : attributes) h.insert(k, Imf::StringAttribute(v));
    Imf::OutputFile out(tmp.c_str(), h);
    Imf::FrameBuffer fb;
    char* base = const_cast<char*>(reinterpret_cast<const char*>(image.rgb.data()));
    size_t xs = 3 * sizeof(float), ys = xs * image.width;
    fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
    fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
    fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
    out.setFrameBuffer(fb);
    out.writePixels(image.height);
  } catch (const std::exception& e) {
    std::remove(tmp.c_str());
    throw Error(path, "", std::string("cannot write EXR: ") + e.what());
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw Error(path, "", "cannot rename " + tmp + ": " + ec.message());
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

HdrImage readPng(const std::string& path) {
  int w = 0, h = 0, n = 0;
  const bool sixteen = stbi_is_16_bit(path.c_str());
  HdrImage img;
  if (sixteen) {
    stbi_us* data = stbi_load_16(path.c_str(), &w, &h, &n, 3);
    if (!data) throw Error(path, "", std::string("cannot read PNG: ") + stbi_failure_reason());
    img = HdrImage(w, h);
    for (size_t i = 0; i < img.rgb.size(); ++i) img.rgb[i] = data[i] / 65535.0f;
    stbi_image_free(data);
  } else {
    stbi_uc* data = stbi_load(path.c_str(), &w, &h, &n, 3);
    if (!data) throw Error(path, "", std::string("cannot read PNG: ") + stbi_failure_reason());
    img = HdrImage(w, h);
    for (size_t i = 0; i < img.rgb.size(); ++i) img.rgb[i] = data[i] / 255.0f;
    stbi_image_free(data);
  }
  return img;
}

}  // namespace nestlight::gi
