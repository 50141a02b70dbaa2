#include "nestlight/viewer/annotations.h"

#include <algorithm>
#include <cmath>
#include <string>

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

}  // namespace

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
    std::string text = a.title;
    if (text.size() > 200) text = text.substr(0, 197) + "...";
    const double tw = stb_easy_font_width(text.data()) * s,
                 th = stb_easy_font_height(text.data()) * s;
    const double bx = at->x + r + 3 * s, by = at->y - r - th - 4 * s;
    fillRect(img, bx, by, bx + tw + 6 * s, by + th + 4 * s, dark, 0.75f);
    static char quads[64 * 1024];
    const int n = stb_easy_font_print(0, 0, text.data(), nullptr, quads, sizeof quads);
    // Each quad: 4 vertices of x, y, z (floats) and a colour (4 bytes); axis-aligned rectangles.
    for (int q = 0; q < n; ++q) {
      const float* v0 = reinterpret_cast<const float*>(quads + q * 64);
      const float* v2 = reinterpret_cast<const float*>(quads + q * 64 + 32);
      fillRect(img, bx + 3 * s + v0[0] * s, by + 2 * s + v0[1] * s, bx + 3 * s + v2[0] * s,
               by + 2 * s + v2[1] * s, white, 1.0f);
    }
  }
  return drawn;
}

}  // namespace nestlight::viewer
