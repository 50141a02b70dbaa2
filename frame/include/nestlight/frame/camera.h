// A perspective camera in world coordinates (double), and the float matrices the GPU gets.
//
// Positions reach the GPU relative to the eye: each node's origin minus the eye is computed in
// double on the CPU and only the small difference becomes float, so a national-grid scan
// (x ~ 5e5 m, mm detail) renders without jitter. The view matrix on the GPU is a pure rotation.
#pragma once

#include <glm/glm.hpp>

#include "nestlight/octree/geometry.h"
#include "nestlight/streaming/view.h"

namespace nestlight::frame {

struct Camera {
  glm::dvec3 eye{0, 0, 0};
  glm::dvec3 target{0, 0, -1};
  glm::dvec3 up{0, 0, 1};  // scans are z-up
  double fovYDegrees = 60;
  double nearPlane = 0.05;
  double farPlane = 1e5;

  // Looks at the centre of `box` from a direction (azimuth/elevation in degrees) from as close as
  // keeps the box's 8 corners inside the frame of aspect `aspect` (width / height) shrunk by
  // `margin` on each side (a fraction of the half-frame): the scan's bounds fill the frame. Near
  // and far follow the box.
  static Camera framing(const Box3d& box, double fovYDegrees = 60, double aspect = 16.0 / 9.0,
                        double azimuth = 35, double elevation = 30, double margin = 0.05);
  // Fits near/far to the box as seen from the current eye.
  void fitClipPlanes(const Box3d& box);

  glm::dmat4 viewRotation() const;                // eye at the origin
  glm::dmat4 projection(double aspect) const;     // OpenGL clip conventions
  glm::dmat4 clipFromWorld(double aspect) const;  // projection * full view (double)
  streaming::View view(int widthPx, int heightPx) const;
};

// The viewer's camera control. Orbit: yaw/pitch/distance around a target; fly: the eye moves and
// the target follows the look. Yaw turns about the camera's `up` (a scene camera's, z for
// scans), pitch rises towards it, so a scene whose camera is not z-up opens and turns as it says.
struct CameraController {
  enum class Mode { Orbit, Fly } mode = Mode::Orbit;
  glm::dvec3 target{0};
  double yaw = 0, pitch = 0, distance = 1;  // degrees, degrees, world units
  double fov = 60;
  double speed = 1;  // fly speed, world units per second
  glm::dvec3 up{0, 0, 1}, side{1, 0, 0},
      front{0, 1, 0};  // yaw 0 looks from `side`, yaw 90 from `front`

  // Takes `c`'s target, eye and up (an up of zero length or along the view: z).
  void from(const Camera& c);
  glm::dvec3 direction() const;  // from target to eye
  Camera camera() const;
};

// Clip-space transform that maps the pixel rectangle [x0, x0 + w) x [y0, y0 + h) of a
// width x height image (y from the bottom) onto the whole viewport: renders a tile of a large
// image with the large image's projection.
glm::dmat4 tileFromClip(int width, int height, int x0, int y0, int w, int h);

}  // namespace nestlight::frame
