// View frustum planes from a clip matrix (Gribb and Hartmann 2001, "Fast Extraction of Viewing
// Frustum Planes from the World-View-Projection Matrix"), and the conservative box test that
// Potree's viewer and most scene graphs use: a box is culled only when it lies wholly outside
// one plane. Double precision: national-grid scans put the camera near 5e6 m.
#include <cmath>
#include <glm/gtc/matrix_access.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "box_cull.h"
#include "nestlight/streaming/view.h"

namespace nestlight::streaming {

Frustum::Frustum(const glm::dmat4& clipFromWorld) {
  // Clip space keeps -w <= x, y, z <= w; each inequality is a plane in world space.
  const glm::dvec4 r0 = glm::row(clipFromWorld, 0), r1 = glm::row(clipFromWorld, 1);
  const glm::dvec4 r2 = glm::row(clipFromWorld, 2), r3 = glm::row(clipFromWorld, 3);
  planes = {r3 + r0, r3 - r0, r3 + r1, r3 - r1, r3 + r2, r3 - r2};
}

bool Frustum::intersects(const Box3d& box) const {
  if (box.empty()) return false;
  const double c[3] = {0.5 * (box.min.x + box.max.x), 0.5 * (box.min.y + box.max.y),
                       0.5 * (box.min.z + box.max.z)};
  const double h[3] = {0.5 * (box.max.x - box.min.x), 0.5 * (box.max.y - box.min.y),
                       0.5 * (box.max.z - box.min.z)};
  uint8_t mask = detail::kAllPlanes;
  return detail::boxInFrustum(*this, c, h, mask);
}

View perspectiveView(const glm::dvec3& eye, const glm::dvec3& target, const glm::dvec3& up,
                     double fovYRadians, int widthPx, int heightPx, double nearZ, double farZ) {
  View v;
  v.eye = eye;
  v.widthPx = widthPx;
  v.heightPx = heightPx;
  v.clipFromWorld = glm::perspective(fovYRadians, double(widthPx) / double(heightPx), nearZ, farZ) *
                    glm::lookAt(eye, target, up);
  v.pixelsPerUnit = heightPx / (2.0 * std::tan(0.5 * fovYRadians));
  return v;
}

}  // namespace nestlight::streaming
