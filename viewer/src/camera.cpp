#include "nestlight/viewer/camera.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

namespace nestlight::viewer {

Camera Camera::framing(const Box3d& box, double fovYDegrees, double azimuth, double elevation) {
  Camera c;
  c.fovYDegrees = fovYDegrees;
  const glm::dvec3 lo(box.min.x, box.min.y, box.min.z), hi(box.max.x, box.max.y, box.max.z);
  const glm::dvec3 centre = (lo + hi) * 0.5;
  const double radius = std::max(glm::length(hi - lo) * 0.5, 1e-6);
  const double distance = radius / std::sin(glm::radians(fovYDegrees) * 0.5);
  const double az = glm::radians(azimuth), el = glm::radians(elevation);
  const glm::dvec3 dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  c.target = centre;
  c.eye = centre + dir * distance;
  c.fitClipPlanes(box);
  return c;
}

void Camera::fitClipPlanes(const Box3d& box) {
  const glm::dvec3 lo(box.min.x, box.min.y, box.min.z), hi(box.max.x, box.max.y, box.max.z);
  const glm::dvec3 centre = (lo + hi) * 0.5;
  const double radius = std::max(glm::length(hi - lo) * 0.5, 1e-6);
  const double d = glm::length(centre - eye);
  farPlane = d + radius * 1.01;
  // Depth precision follows far/near; 1e-4 of the far plane keeps 24+ bits useful.
  nearPlane = std::max(d - radius * 1.01, farPlane * 1e-4);
}

glm::dmat4 Camera::viewRotation() const { return glm::lookAt(glm::dvec3(0), target - eye, up); }

glm::dmat4 Camera::projection(double aspect) const {
  return glm::perspective(glm::radians(fovYDegrees), aspect, nearPlane, farPlane);
}

glm::dmat4 Camera::clipFromWorld(double aspect) const {
  return projection(aspect) * glm::lookAt(eye, target, up);
}

streaming::View Camera::view(int widthPx, int heightPx) const {
  streaming::View v;
  v.clipFromWorld = clipFromWorld(double(widthPx) / heightPx);
  v.eye = eye;
  v.widthPx = widthPx;
  v.heightPx = heightPx;
  v.pixelsPerUnit = heightPx / (2.0 * std::tan(glm::radians(fovYDegrees) * 0.5));
  return v;
}

glm::dmat4 tileFromClip(int width, int height, int x0, int y0, int w, int h) {
  // x_tile = x_ndc * W/w + (W - 2 x0)/w - 1. In clip space the offset multiplies w_clip, so it
  // sits in column 3 (glm is column-major: m[column][row]).
  glm::dmat4 m(1.0);
  m[0][0] = double(width) / w;
  m[1][1] = double(height) / h;
  m[3][0] = (double(width) - 2.0 * x0) / w - 1.0;
  m[3][1] = (double(height) - 2.0 * y0) / h - 1.0;
  return m;
}

}  // namespace nestlight::viewer
