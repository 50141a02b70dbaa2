// Cones of directions: the normals below a node of the bounding-sphere hierarchy, and the normals
// under a texel of the G-buffer's cone mip pyramid (Sabbadin et al., "High Dynamic Range Point
// Clouds for Real-Time Relighting", 2019, sections 5.1 and 5.2.1).
//
// Barequet and Elber (2005) compute the minimum cone bounding a set of vectors. Bottom-up, every
// cone here bounds two children cones, and the smallest cone containing two cones has a closed
// form (the axis in their common plane, the half aperture half the angle they span): each merge
// is exact for its two inputs, and the result always contains every normal below, though it can
// be wider than the minimum cone of those normals themselves (by at most what the children's own
// slack was). That keeps fills O(1) per node on loader threads.
#pragma once

#include <glm/glm.hpp>

#include "nestlight/gi/sampling.h"  // kPi

namespace nestlight::gi {

struct NormalCone {
  glm::vec3 axis{0, 0, 1};  // unit
  float halfAngle = kPi;    // radians in [0, pi]; pi bounds nothing (every direction)

  // The cone of one unit normal; a zero or non-finite vector gives the cone of every direction.
  static NormalCone of(const glm::vec3& normal);
  static NormalCone everything() { return {}; }
  bool boundsNothing() const { return halfAngle >= kPi; }
  // Whether the unit vector lies inside, with `slack` radians of tolerance.
  bool contains(const glm::vec3& v, float slack = 0) const;
  bool contains(const NormalCone& c, float slack = 0) const;
};

// The smallest cone containing both.
NormalCone merge(const NormalCone& a, const NormalCone& b);

}  // namespace nestlight::gi
