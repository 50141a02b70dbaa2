#include "nestlight/frame/camera.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>

namespace nestlight::frame {

Camera Camera::framing(const Box3d& box, double fovYDegrees, double aspect, double azimuth,
                       double elevation, double margin) {
  Camera c;
  c.fovYDegrees = fovYDegrees;
  const glm::dvec3 lo(box.min.x, box.min.y, box.min.z), hi(box.max.x, box.max.y, box.max.z);
  const glm::dvec3 centre = (lo + hi) * 0.5;
  // Straight down or up has no screen "up" for a z-up camera (glm::lookAt degenerates, and the
  // viewer's orbit controller rebuilds its camera with z up): stop just short of the pole.
  const double az = glm::radians(azimuth), el = glm::radians(std::clamp(elevation, -89.9, 89.9));
  const glm::dvec3 dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  // The camera's axes for this direction (as glm::lookAt builds them; straight down or up picks
  // +y as the screen's up so that the basis stays defined).
  const glm::dvec3 forward = -dir;
  glm::dvec3 right = glm::cross(forward, c.up);
  if (glm::length(right) < 1e-9) right = glm::cross(forward, glm::dvec3(0, 1, 0));
  right = glm::normalize(right);
  const glm::dvec3 upAxis = glm::cross(right, forward);
  // The nearest eye that keeps all 8 corners inside the frame shrunk by `margin`, panning in the
  // image plane as well as moving back. With a corner at (x, y) across the view and t towards
  // the camera from the centre, an eye at distance D and pan (a, b) sees it at depth D - t, and
  // the corner is inside when |x - a| <= T (D - t), T = tan(fovX / 2) (likewise y with fovY).
  // So D >= (max(x + T t) - min(x - T t)) / 2T, with a = (max(x + T t) + min(x - T t)) / 2: the
  // binding axis touches both edges of the frame. Fitting a bounding sphere instead leaves a flat
  // scan (an airborne strip, a facade) small in the middle of the frame.
  const double tanY = std::tan(glm::radians(fovYDegrees) * 0.5) * (1.0 - margin);
  const double tanX = tanY * std::max(aspect, 1e-6);
  double hiX = -INFINITY, loX = INFINITY, hiY = -INFINITY, loY = INFINITY;
  for (int k = 0; k < 8; ++k) {
    const glm::dvec3 corner((k & 4) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 1) ? hi.z : lo.z);
    const glm::dvec3 o = corner - centre;
    const double x = glm::dot(o, right), y = glm::dot(o, upAxis), t = glm::dot(o, dir);
    hiX = std::max(hiX, x + tanX * t), loX = std::min(loX, x - tanX * t);
    hiY = std::max(hiY, y + tanY * t), loY = std::min(loY, y - tanY * t);
  }
  // A scan of one point (or of coincident ones) has no extent to fit: stand off by a distance
  // that doubles and the GPU's float offsets still resolve at the scan's coordinates.
  const double radius = glm::length(hi - lo) * 0.5;
  const double magnitude =
      std::max({std::fabs(centre.x), std::fabs(centre.y), std::fabs(centre.z)});
  const double distance = std::max(
      {(hiX - loX) / (2 * tanX), (hiY - loY) / (2 * tanY), 1e-3 * radius, 1e-6 * magnitude, 1e-3});
  c.target = centre + right * (0.5 * (hiX + loX)) + upAxis * (0.5 * (hiY + loY));
  c.eye = c.target + dir * distance;
  if (glm::length(glm::cross(forward, c.up)) < 1e-9) c.up = upAxis;
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

glm::dmat4 Camera::viewRotation() const {
  return glm::lookAt(glm::dvec3(0), target - eye, up);
}

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

void CameraController::from(const Camera& c) {
  target = c.target;
  const glm::dvec3 d = c.eye - c.target;
  distance = std::max(glm::length(d), 1e-6);
  glm::dvec3 u = c.up;
  const double len = glm::length(u);
  if (!(len > 0) || !std::isfinite(len)) u = {0, 0, 1};
  u = glm::normalize(u);
  // The frame about `up`: for z-up, side = x and front = y, as the viewer always turned.
  glm::dvec3 x{1, 0, 0};
  if (std::abs(glm::dot(x, u)) > 0.99) x = {0, 1, 0};
  up = u;
  side = glm::normalize(x - glm::dot(x, u) * u);
  front = glm::cross(up, side);
  yaw = glm::degrees(std::atan2(glm::dot(d, front), glm::dot(d, side)));
  pitch = glm::degrees(std::asin(std::clamp(glm::dot(d, up) / distance, -1.0, 1.0)));
  fov = c.fovYDegrees;
}

glm::dvec3 CameraController::direction() const {
  const double y = glm::radians(yaw), p = glm::radians(pitch);
  return std::cos(p) * std::cos(y) * side + std::cos(p) * std::sin(y) * front + std::sin(p) * up;
}

Camera CameraController::camera() const {
  Camera c;
  c.fovYDegrees = fov;
  c.target = target;
  c.eye = target + direction() * distance;
  c.up = up;
  return c;
}

}  // namespace nestlight::frame
