#include "nestlight/converters/profile.h"

#include <stb_image_write.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <memory>

#include "nestlight/converters/point_writer.h"
#include "nestlight/converters/progress.h"
#include "nestlight/octree/crs.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight {
namespace {

namespace fs = std::filesystem;

std::string lowerExtension(const fs::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e;
}

// A perceptually ordered ramp (dark blue, cyan, green, yellow, red) for heights.
std::array<uint8_t, 3> ramp(double t) {
  static const double stops[5][3] = {{0.15, 0.20, 0.60},
                                     {0.10, 0.65, 0.85},
                                     {0.25, 0.75, 0.30},
                                     {0.95, 0.85, 0.20},
                                     {0.85, 0.20, 0.15}};
  t = std::clamp(t, 0.0, 1.0) * 4;
  const int i = std::min(3, int(t));
  const double f = t - i;
  std::array<uint8_t, 3> c;
  for (int k = 0; k < 3; ++k)
    c[k] = uint8_t(std::lround(255 * (stops[i][k] * (1 - f) + stops[i + 1][k] * f)));
  return c;
}

// Steps of 1, 2 or 5 times a power of ten giving about `n` ticks over `span`.
double niceStep(double span, int n) {
  if (!(span > 0)) return 1;
  const double raw = span / n, p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (raw <= m * p) return m * p;
  return 10 * p;
}

std::string base64(const std::vector<uint8_t>& in) {
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  for (size_t i = 0; i < in.size(); i += 3) {
    const uint32_t v = uint32_t(in[i]) << 16 | (i + 1 < in.size() ? uint32_t(in[i + 1]) << 8 : 0) |
                       (i + 2 < in.size() ? in[i + 2] : 0);
    out += t[v >> 18 & 63];
    out += t[v >> 12 & 63];
    out += i + 1 < in.size() ? t[v >> 6 & 63] : '=';
    out += i + 2 < in.size() ? t[v & 63] : '=';
  }
  return out;
}

std::string fmt(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.10g", std::abs(v) < 1e-12 ? 0.0 : v);
  return b;
}

struct Plot {
  int w = 0, h = 0;
  double a0 = 0, z0 = 0, scaleX = 1, scaleZ = 1;  // pixel = (along - a0) * scaleX, ...
  std::vector<uint8_t> rgb;
  std::vector<float> depth;
};

void writeSvg(const fs::path& file, const Plot& plot, const std::vector<uint8_t>& png,
              const ProfileReport& r, const ProfileOptions& o, const std::string& title) {
  const int left = 80, right = 24, top = 40, bottom = 56;
  const int W = plot.w + left + right, H = plot.h + top + bottom;
  std::string s = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(W) +
                  "\" height=\"" + std::to_string(H) +
                  "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  s += "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  s += "<text x=\"" + std::to_string(left) + "\" y=\"22\" font-size=\"14\">" + title + "</text>\n";
  s += "<image x=\"" + std::to_string(left) + "\" y=\"" + std::to_string(top) + "\" width=\"" +
       std::to_string(plot.w) + "\" height=\"" + std::to_string(plot.h) +
       "\" image-rendering=\"pixelated\" href=\"data:image/png;base64," + base64(png) + "\"/>\n";
  s += "<rect x=\"" + std::to_string(left) + "\" y=\"" + std::to_string(top) + "\" width=\"" +
       std::to_string(plot.w) + "\" height=\"" + std::to_string(plot.h) +
       "\" fill=\"none\" stroke=\"black\"/>\n";
  const double a1 = plot.a0 + plot.w / plot.scaleX, z1 = plot.z0 + plot.h / plot.scaleZ;
  const double sa = niceStep(a1 - plot.a0, 10),
               sz = niceStep(z1 - plot.z0, std::max(2, plot.h / 60));
  for (double a = std::ceil(plot.a0 / sa) * sa; a <= a1 + 1e-9 * sa; a += sa) {
    const double x = left + (a - plot.a0) * plot.scaleX;
    s += "<line x1=\"" + fmt(x) + "\" y1=\"" + std::to_string(top + plot.h) + "\" x2=\"" + fmt(x) +
         "\" y2=\"" + std::to_string(top + plot.h + 5) + "\" stroke=\"black\"/>";
    s += "<text x=\"" + fmt(x) + "\" y=\"" + std::to_string(top + plot.h + 18) +
         "\" text-anchor=\"middle\">" + fmt(a) + "</text>\n";
  }
  for (double z = std::ceil(plot.z0 / sz) * sz; z <= z1 + 1e-9 * sz; z += sz) {
    const double y = top + plot.h - (z - plot.z0) * plot.scaleZ;
    s += "<line x1=\"" + std::to_string(left - 5) + "\" y1=\"" + fmt(y) + "\" x2=\"" +
         std::to_string(left) + "\" y2=\"" + fmt(y) + "\" stroke=\"black\"/>";
    s += "<text x=\"" + std::to_string(left - 8) + "\" y=\"" + fmt(y + 4) +
         "\" text-anchor=\"end\">" + fmt(z) + "</text>\n";
  }
  s += "<text x=\"" + std::to_string(left + plot.w / 2) + "\" y=\"" + std::to_string(H - 12) +
       "\" text-anchor=\"middle\">distance along the line (" + r.unit + ")</text>\n";
  s += "<text transform=\"translate(16," + std::to_string(top + plot.h / 2) +
       ") rotate(-90)\" text-anchor=\"middle\">height (" + r.unit + ")" +
       (o.exaggeration != 1 ? ", exaggerated " + fmt(o.exaggeration) + "x" : std::string()) +
       "</text>\n";
  if (r.points == 0)
    s += "<text x=\"" + std::to_string(left + plot.w / 2) + "\" y=\"" +
         std::to_string(top + plot.h / 2) +
         "\" text-anchor=\"middle\">no point within the corridor</text>\n";
  s += "</svg>\n";
  const fs::path tmp = file.string() + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary);
    f << s;
    if (!f) throw Error(file.string(), "", "cannot write");
  }
  fs::rename(tmp, file);
}

}  // namespace

ProfileReport profileOctree(const fs::path& dir, const ProfileOptions& o) {
  ClipSet clip;
  clip.volumes.push_back(ClipVolume::corridor(o.line, o.width, o.zMin, o.zMax));
  clip.volumes[0].validate("--line", "");
  const ClipVolume& corridor = clip.volumes[0];
  std::vector<fs::path> pointFiles, pngFiles, svgFiles;
  for (const fs::path& p : o.outputs) {
    const std::string e = lowerExtension(p);
    if (e == ".las" || e == ".laz" || e == ".ply")
      pointFiles.push_back(p);
    else if (e == ".png")
      pngFiles.push_back(p);
    else if (e == ".svg")
      svgFiles.push_back(p);
    else
      throw Error(p.string(), "",
                  "cannot tell the output from the extension '" + e +
                      "': name a .las, .laz or .ply file (the points) or a .png or .svg file "
                      "(the plot)");
  }
  Metadata m;
  {
    OctreeReader reader(dir);
    m = reader.metadata();
  }
  ProfileReport r;
  r.length = corridor.length();
  r.unit = o.unit.empty() ? describeCrs(m.crs).unitSymbol() : o.unit;
  const int rgbIndex = m.layout.find("rgb"), intensityIndex = m.layout.find("intensity");
  r.colour = o.colour;
  if (r.colour == "auto") r.colour = rgbIndex >= 0 ? "rgb" : "elevation";
  if (r.colour == "rgb" && rgbIndex < 0)
    throw Error(dir.string(), "", "--colour rgb: the octree has no rgb attribute");
  if (r.colour == "intensity" && intensityIndex < 0)
    throw Error(dir.string(), "", "--colour intensity: the octree has no intensity attribute");

  // Pass 1: the points, with their distance along the line, and the plot's extent.
  SourceHeader h;
  h.format = "octree";
  h.layout = m.layout;
  for (const auto& l : m.layers)
    h.layout.add({l.name, ScalarType::F32, 3, "colour layer '" + l.name + "': linear RGB"});
  const size_t inStride = h.layout.stride();
  h.layout.add({"distance", ScalarType::F64, 1, "distance along the profile's line"});
  const size_t outStride = h.layout.stride();
  h.rgbBits = m.rgbSourceBits;
  h.scale = m.scale;
  h.offset = m.sourceOffset.value_or(m.offset);
  h.crs = m.crs;
  std::vector<std::unique_ptr<PointWriter>> writers;
  for (const fs::path& p : pointFiles) {
    h.path = p.string();
    writers.push_back(createWriter(p.string(), h));
  }
  ExportOptions eo;
  eo.clip = &clip;
  eo.progress = o.progress;
  eo.threads = o.threads;
  double zLo = INFINITY, zHi = -INFINITY, aLo = INFINITY, aHi = -INFINITY;
  r.walk = walkClipped(
      dir, eo,
      [&](ClippedNode& n) {
        const size_t k = n.batch.size();
        std::vector<uint8_t> attrs(k * outStride);
        n.extra.resize(k);
        for (size_t i = 0; i < k; ++i) {
          const double along = corridor.along({n.batch.xyz[3 * i], n.batch.xyz[3 * i + 1], 0});
          n.extra[i] = along;
          std::memcpy(&attrs[i * outStride], &n.batch.attrs[i * inStride], inStride);
          std::memcpy(&attrs[i * outStride + inStride], &along, 8);
        }
        n.batch.attrs = std::move(attrs);
      },
      [&](ClippedNode& n) {
        for (auto& w : writers) w->write(n.batch);
        for (size_t i = 0; i < n.batch.size(); ++i) {
          zLo = std::min(zLo, n.batch.xyz[3 * i + 2]), zHi = std::max(zHi, n.batch.xyz[3 * i + 2]);
          aLo = std::min(aLo, n.extra[i]), aHi = std::max(aHi, n.extra[i]);
        }
      });
  for (auto& w : writers) w->close();
  r.points = r.walk.points;
  if (r.points) r.zMin = zLo, r.zMax = zHi, r.alongMin = aLo, r.alongMax = aHi;
  if (pngFiles.empty() && svgFiles.empty()) return r;

  // Pass 2: the plot. Seen from the right of the line (its start at the plot's left), the
  // nearest point of each pixel wins.
  Plot plot;
  plot.w = std::max(16, o.imageWidth);
  const double a0 = r.points ? aLo : 0, a1 = r.points ? aHi : r.length;
  const double pad = std::max(1e-6, 0.01 * (a1 - a0));
  plot.a0 = a0 - pad;
  plot.scaleX = plot.w / (a1 - a0 + 2 * pad);
  const double z0 = r.points ? zLo : 0, z1 = r.points ? zHi : 1;
  const double zpad = std::max(1e-6, 0.02 * (z1 - z0));
  plot.scaleZ = plot.scaleX * o.exaggeration;
  plot.h = int(std::ceil((z1 - z0 + 2 * zpad) * plot.scaleZ));
  if (plot.h > 8192 || plot.h < 48) {
    // A flat or a tall section: the height is clamped and the vertical scale follows.
    plot.h = std::clamp(plot.h, 48, 8192);
    plot.scaleZ = plot.h / (z1 - z0 + 2 * zpad);
  }
  plot.z0 = z0 - zpad;
  r.imageWidth = plot.w, r.imageHeight = plot.h;
  plot.rgb.assign(size_t(plot.w) * plot.h * 3, 255);
  plot.depth.assign(size_t(plot.w) * plot.h, INFINITY);
  if (r.points) {
    const size_t rgbAt = rgbIndex >= 0 ? m.layout.offset(rgbIndex) : 0;
    const size_t intensityAt = intensityIndex >= 0 ? m.layout.offset(intensityIndex) : 0;
    // Each point covers a square of the finest level's spacing (1 to 8 pixels): a sparse scan
    // still reads as surfaces, a dense one as single pixels.
    const int side = std::clamp(int(std::ceil(m.levelSpacing(m.depth) * plot.scaleX)), 1, 8);
    const int half = side / 2;
    eo.progress = nullptr;
    walkClipped(dir, eo, nullptr, [&](ClippedNode& n) {
      for (size_t i = 0; i < n.batch.size(); ++i) {
        const Vec3d p{n.batch.xyz[3 * i], n.batch.xyz[3 * i + 1], n.batch.xyz[3 * i + 2]};
        const auto [along, across] = corridor.alongAcross(p);
        const int x = int((along - plot.a0) * plot.scaleX);
        const int y = plot.h - 1 - int((p.z - plot.z0) * plot.scaleZ);
        if (x < 0 || y < 0 || x >= plot.w || y >= plot.h) continue;
        const uint8_t* a = &n.batch.attrs[i * inStride];
        std::array<uint8_t, 3> c;
        if (r.colour == "rgb") {
          for (int k = 0; k < 3; ++k) {
            uint16_t v;
            std::memcpy(&v, a + rgbAt + 2 * k, 2);
            c[k] = uint8_t(v >> 8);
          }
        } else if (r.colour == "intensity") {
          uint16_t v;
          std::memcpy(&v, a + intensityAt, 2);
          c.fill(uint8_t(v >> 8));
        } else {
          c = ramp((p.z - zLo) / std::max(1e-12, zHi - zLo));
        }
        for (int dy = -half; dy < side - half; ++dy)
          for (int dx = -half; dx < side - half; ++dx) {
            const int sx = x + dx, sy = y + dy;
            if (sx < 0 || sy < 0 || sx >= plot.w || sy >= plot.h) continue;
            const size_t px = size_t(sy) * plot.w + sx;
            if (!(across < plot.depth[px])) continue;
            plot.depth[px] = float(across);
            std::memcpy(&plot.rgb[px * 3], c.data(), 3);
          }
      }
    });
  }
  std::vector<uint8_t> png;
  stbi_write_png_to_func(
      [](void* ctx, void* data, int size) {
        auto* v = static_cast<std::vector<uint8_t>*>(ctx);
        v->insert(v->end(), static_cast<uint8_t*>(data), static_cast<uint8_t*>(data) + size);
      },
      &png, plot.w, plot.h, 3, plot.rgb.data(), plot.w * 3);
  if (png.empty()) throw Error("profile: the plot could not be encoded as PNG");
  for (const fs::path& p : pngFiles) {
    const fs::path tmp = p.string() + ".tmp";
    {
      std::ofstream f(tmp, std::ios::binary);
      f.write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
      if (!f) throw Error(p.string(), "", "cannot write");
    }
    fs::rename(tmp, p);
  }
  const std::string title = dir.filename().string() + ": " + std::to_string(r.points) +
                            " points within " + fmt(o.width / 2) + " " + r.unit + " of a " +
                            fmt(r.length) + " " + r.unit + " line";
  for (const fs::path& p : svgFiles) writeSvg(p, plot, png, r, o, title);
  return r;
}

}  // namespace nestlight
