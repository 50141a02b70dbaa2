#include "nestlight/viewer/annotations.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#endif
#include <stb_easy_font.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

namespace nestlight::viewer {

std::optional<glm::dvec2> projectToImage(const frame::Camera& camera, int width, int height,
                                         const Vec3d& world) {
  const glm::dvec3 v =
      glm::dmat3(camera.viewRotation()) * (glm::dvec3(world.x, world.y, world.z) - camera.eye);
  if (!(-v.z > 0)) return std::nullopt;
  const glm::dvec4 clip = camera.projection(double(width) / height) * glm::dvec4(v, 1.0);
  const glm::dvec2 p((clip.x / clip.w * 0.5 + 0.5) * width, (0.5 - clip.y / clip.w * 0.5) * height);
  if (p.x < 0 || p.y < 0 || p.x >= width || p.y >= height) return std::nullopt;
  return p;
}

namespace {

void blend(frame::Image& img, int x, int y, const float rgb[3], float alpha) {
  if (x < 0 || y < 0 || x >= img.width || y >= img.height) return;
  float* p = img.at(x, y);
  for (int c = 0; c < 3; ++c) p[c] = p[c] * (1 - alpha) + rgb[c] * alpha;
  p[3] = std::max(p[3], alpha);
}

void fillRect(frame::Image& img, double x0, double y0, double x1, double y1, const float rgb[3],
              float alpha) {
  for (int y = int(std::floor(y0)); y < int(std::ceil(y1)); ++y)
    for (int x = int(std::floor(x0)); x < int(std::ceil(x1)); ++x) blend(img, x, y, rgb, alpha);
}

// A line `width` pixels wide from a to b (image pixels), clipped to the image first
// (Liang-Barsky): a segment that passes close to the eye projects to enormous coordinates.
void drawLine(frame::Image& img, glm::dvec2 a, glm::dvec2 b, double width, const float rgb[3]) {
  const glm::dvec2 lo(-width, -width), hi(img.width + width, img.height + width), d = b - a;
  double t0 = 0, t1 = 1;
  for (int k = 0; k < 2; ++k) {
    for (const auto& [p, q] : {std::pair{-d[k], a[k] - lo[k]}, std::pair{d[k], hi[k] - a[k]}}) {
      if (p == 0) {
        if (q < 0) return;  // parallel to this edge and outside it
      } else if (p < 0) {
        t0 = std::max(t0, q / p);
      } else {
        t1 = std::min(t1, q / p);
      }
    }
  }
  if (!(t0 <= t1)) return;
  b = a + d * t1, a = a + d * t0;
  const double len = glm::length(b - a);
  const int steps = int(std::ceil(len * 2)) + 1;
  for (int i = 0; i <= steps; ++i) {
    const glm::dvec2 p = a + (b - a) * (double(i) / steps);
    fillRect(img, p.x - width / 2, p.y - width / 2, p.x + width / 2, p.y + width / 2, rgb, 1.0f);
  }
}

// Where the segment a-b crosses into the half-space in front of the eye, in image pixels: a line
// to a point behind the camera is cut at the near plane rather than dropped.
std::optional<std::pair<glm::dvec2, glm::dvec2>> projectSegment(const frame::Camera& cam, int w,
                                                                int h, const Vec3d& a,
                                                                const Vec3d& b) {
  const glm::dmat3 rot(cam.viewRotation());
  glm::dvec3 va = rot * (glm::dvec3(a.x, a.y, a.z) - cam.eye),
             vb = rot * (glm::dvec3(b.x, b.y, b.z) - cam.eye);
  const double zn = -cam.nearPlane;
  if (va.z > zn && vb.z > zn) return std::nullopt;
  if (va.z > zn) va = vb + (va - vb) * ((zn - vb.z) / (va.z - vb.z));
  if (vb.z > zn) vb = va + (vb - va) * ((zn - va.z) / (vb.z - va.z));
  const glm::dmat4 proj = cam.projection(double(w) / h);
  auto px = [&](const glm::dvec3& v) {
    const glm::dvec4 c = proj * glm::dvec4(v, 1.0);
    return glm::dvec2((c.x / c.w * 0.5 + 0.5) * w, (0.5 - c.y / c.w * 0.5) * h);
  };
  return std::make_pair(px(va), px(vb));
}

void drawLabel(frame::Image& img, double x, double y, double s, const std::string& title,
               const float box[3], const float ink[3]) {
  // stb_easy_font draws printable ASCII only (other bytes would index outside its glyph table):
  // a superscript two becomes "^2", anything else outside ASCII "?".
  std::string text;
  for (size_t i = 0; i < title.size() && text.size() < 200; ++i) {
    const unsigned char c = static_cast<unsigned char>(title[i]);
    if (c == 0xC2 && i + 1 < title.size() && static_cast<unsigned char>(title[i + 1]) == 0xB2) {
      text += "^2";
      ++i;
    } else if (c >= 32 && c < 127) {
      text += char(c);
    } else if (c < 0x80 || c >= 0xC0) {
      text += '?';  // one mark per character: UTF-8 continuation bytes add none
    }
  }
  const double tw = stb_easy_font_width(text.data()) * s,
               th = stb_easy_font_height(text.data()) * s;
  // Kept inside the image: a label by a point near the right edge moves left.
  x = std::clamp(x, 0.0, std::max(0.0, img.width - tw - 6 * s));
  y = std::clamp(y, 0.0, std::max(0.0, img.height - th - 4 * s));
  fillRect(img, x, y, x + tw + 6 * s, y + th + 4 * s, box, 0.75f);
  alignas(16) static thread_local char quads[64 * 1024];
  const int n = stb_easy_font_print(0, 0, text.data(), nullptr, quads, sizeof quads);
  // Each quad: 4 vertices of x, y, z (floats) and a colour (4 bytes); axis-aligned rectangles.
  for (int q = 0; q < n; ++q) {
    const float* v0 = reinterpret_cast<const float*>(quads + q * 64);
    const float* v2 = reinterpret_cast<const float*>(quads + q * 64 + 32);
    fillRect(img, x + 3 * s + v0[0] * s, y + 2 * s + v0[1] * s, x + 3 * s + v2[0] * s,
             y + 2 * s + v2[1] * s, ink, 1.0f);
  }
}

}  // namespace

std::string measurementLabel(const Measurement& m, const std::string& unit) {
  if (!m.complete()) return "";
  const double v = m.measure().value;
  char b[96];
  switch (m.kind) {
    case Measurement::Kind::Area:
      std::snprintf(b, sizeof b, "%.3f %s^2", v, unit.c_str());
      break;
    case Measurement::Kind::Height:
      std::snprintf(b, sizeof b, "dz %.3f %s", v, unit.c_str());
      break;
    case Measurement::Kind::Angle:
      std::snprintf(b, sizeof b, "%.1f deg", v);
      break;
    default:
      std::snprintf(b, sizeof b, "%.3f %s", v, unit.c_str());
  }
  return b;
}

int drawMeasurements(frame::Image& img, const frame::Camera& camera,
                     const std::vector<Measurement>& measurements, const std::string& unit) {
  const float line[3] = {0.2f, 0.9f, 1.0f}, dark[3] = {0.05f, 0.05f, 0.07f}, white[3] = {1, 1, 1};
  const double s = std::max(1.0, std::round(img.height / 400.0));
  int drawn = 0;
  for (const Measurement& m : measurements) {
    const size_t n = m.points.size();
    if (n == 0) continue;
    const bool closed = m.kind == Measurement::Kind::Area && n >= 3;
    for (size_t i = 0; i + 1 < n + (closed ? 1 : 0); ++i) {
      const auto seg =
          projectSegment(camera, img.width, img.height, m.points[i], m.points[(i + 1) % n]);
      if (seg) drawLine(img, seg->first, seg->second, 1.5 * s, line);
    }
    bool any = false;
    for (const Vec3d& p : m.points)
      if (const auto at = projectToImage(camera, img.width, img.height, p)) {
        any = true;
        fillRect(img, at->x - 2 * s, at->y - 2 * s, at->x + 2 * s, at->y + 2 * s, white, 1.0f);
      }
    if (!any) continue;
    ++drawn;
    const auto last = projectToImage(camera, img.width, img.height, m.points.back());
    if (last && m.complete())
      drawLabel(img, last->x + 5 * s, last->y + 3 * s, s, measurementLabel(m, unit), dark, white);
  }
  return drawn;
}

int drawAnnotations(frame::Image& img, const frame::Camera& camera,
                    const std::vector<frame::Annotation>& annotations) {
  const float white[3] = {1, 1, 1}, dark[3] = {0.05f, 0.05f, 0.07f},
              accent[3] = {1.0f, 0.75f, 0.1f};
  const double s = std::max(1.0, std::round(img.height / 400.0));  // text scale
  int drawn = 0;
  for (const frame::Annotation& a : annotations) {
    const auto at = projectToImage(camera, img.width, img.height, a.position);
    if (!at) continue;
    ++drawn;
    // The marker: a ring around the point.
    const double r = 4 * s;
    for (int y = int(at->y - r - 1); y <= int(at->y + r + 1); ++y)
      for (int x = int(at->x - r - 1); x <= int(at->x + r + 1); ++x) {
        const double d = std::hypot(x + 0.5 - at->x, y + 0.5 - at->y);
        if (d <= r + 0.5) blend(img, x, y, d >= r - 1.5 * s ? accent : dark, 0.9f);
      }
    // The title in a dark box up and right of the marker.
    const double th = 12 * s;  // stb_easy_font's line height
    drawLabel(img, at->x + r + 3 * s, at->y - r - th - 4 * s, s, a.title, dark, white);
  }
  return drawn;
}

}  // namespace nestlight::viewer
