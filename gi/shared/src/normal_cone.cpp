#include "nestlight/gi/shared/normal_cone.h"

#include <algorithm>
#include <cmath>

namespace nestlight::gi {

namespace {

// Angle between unit vectors, from the cross product's length and the dot product: precise near 0
// and pi, where acos is not.
float angleBetween(const glm::vec3& a, const glm::vec3& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

}  // namespace

NormalCone NormalCone::of(const glm::vec3& n) {
  const float len = glm::length(n);
  if (!(len > 0) || !std::isfinite(len)) return everything();
  return {n / len, 0.0f};
}

bool NormalCone::contains(const glm::vec3& v, float slack) const {
  if (boundsNothing()) return true;
  return angleBetween(axis, v) <= halfAngle + slack;
}

bool NormalCone::contains(const NormalCone& c, float slack) const {
  if (boundsNothing()) return true;
  if (c.boundsNothing()) return false;
  return angleBetween(axis, c.axis) + c.halfAngle <= halfAngle + slack;
}

NormalCone merge(const NormalCone& a, const NormalCone& b) {
  if (a.boundsNothing() || b.boundsNothing()) return NormalCone::everything();
  // In double: near-opposite axes make the rotation plane's normal a small difference.
  const glm::dvec3 aa = glm::normalize(glm::dvec3(a.axis)), ba = glm::normalize(glm::dvec3(b.axis));
  const double theta = std::atan2(glm::length(glm::cross(aa, ba)), glm::dot(aa, ba));
  if (theta + b.halfAngle <= a.halfAngle) return a;
  if (theta + a.halfAngle <= b.halfAngle) return b;
  const double half = 0.5 * (theta + a.halfAngle + b.halfAngle);
  if (half >= kPi) return NormalCone::everything();
  // Opposite axes: any great circle through both would do.
  glm::dvec3 perp = ba - glm::dot(aa, ba) * aa;
  double plen = glm::length(perp);
  if (!(plen > 1e-12)) {
    perp = std::fabs(aa.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
    perp -= glm::dot(perp, aa) * aa;
    plen = glm::length(perp);
  }
  perp /= plen;
  // Rotate a's axis towards b's by (half - a.halfAngle): the new cone's edge then touches a's far
  // edge and b's far edge. The float axis is then within ~1e-7 rad of the double one: widen by
  // 1e-6 so the cone still contains both.
  const double rot = half - a.halfAngle;
  NormalCone out;
  out.axis = glm::vec3(glm::normalize(std::cos(rot) * aa + std::sin(rot) * perp));
  out.halfAngle = float(std::min(half + 1e-6, double(kPi)));
  return out;
}

}  // namespace nestlight::gi
