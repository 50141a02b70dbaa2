// What the scheduler needs to know about a frame's camera: a frustum and a scale from world
// lengths at a distance to pixels. Double precision throughout: national-grid scans have
// coordinates near 5e6 m and millimetre detail.
#pragma once

#include <array>
#include <glm/glm.hpp>

#include "nestlight/octree/clip_volume.h"
#include "nestlight/octree/geometry.h"

namespace nestlight::streaming {

struct View {
  glm::dmat4 clipFromWorld{1.0};  // projection * view, OpenGL clip conventions (-w <= z <= w)
  glm::dvec3 eye{0.0};            // camera position, world units
  int widthPx = 1;
  int heightPx = 1;
  // Pixels covered by one world unit at distance 1 in front of a perspective camera:
  // heightPx / (2 tan(fovY / 2)). For an orthographic camera, pixels per world unit.
  double pixelsPerUnit = 1.0;
  bool orthographic = false;
  // Clipping volumes: nodes whose cube they remove whole are left out of the cut (and so never
  // loaded); the renderer clips the rest point by point. Not owned; null or empty: no clipping.
  const ClipSet* clip = nullptr;

  // Projected size in pixels of a length `worldLength` at `distance` from the eye.
  double projectedPixels(double worldLength, double distance) const {
    return orthographic ? worldLength * pixelsPerUnit
                        : worldLength * pixelsPerUnit / (distance > 1e-9 ? distance : 1e-9);
  }
};

// A perspective camera at `eye` looking at `target` (OpenGL conventions, as glm::perspective and
// glm::lookAt build them), for tests, the stress tool and benchmarks.
View perspectiveView(const glm::dvec3& eye, const glm::dvec3& target, const glm::dvec3& up,
                     double fovYRadians, int widthPx, int heightPx, double nearZ, double farZ);

// The six planes of a view's frustum (a x + b y + c z + d >= 0 inside), from clipFromWorld.
struct Frustum {
  std::array<glm::dvec4, 6> planes;
  explicit Frustum(const glm::dmat4& clipFromWorld);
  // False only when the box lies entirely outside one plane (conservative).
  bool intersects(const Box3d& box) const;
};

}  // namespace nestlight::streaming
