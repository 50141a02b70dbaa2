// Texel solid angles of the hemi-octahedral map: Maletz, Wang and Bowers, "Importance-Driven
// Point Projection for GPU-based Final Gathering" (2011), section 4.2, eq. 2; the solid angle of a
// planar triangle: Van Oosterom and Strackee, "The Solid Angle of a Plane Triangle" (1983).
#include "nestlight/gi/projection/hemi_octahedral.h"

#include <cmath>
#include <glm/glm.hpp>

#include "nestlight/octree/error.h"

namespace nestlight::gi::projection {

namespace {

using Polygon = std::vector<glm::dvec2>;  // (x, z) on the octahedron's upper half, projected

// Keeps the part of `poly` where sign * p[axis] >= 0.
Polygon clip(const Polygon& poly, int axis, double sign) {
  Polygon out;
  const size_t n = poly.size();
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec2 p = poly[i], q = poly[(i + 1) % n];
    const double fp = sign * p[axis], fq = sign * q[axis];
    if (fp >= 0) out.push_back(p);
    if ((fp >= 0) != (fq >= 0)) out.push_back(p + (fp / (fp - fq)) * (q - p));
  }
  return out;
}

glm::dvec3 lift(glm::dvec2 p) {
  return {p.x, std::max(0.0, 1.0 - std::abs(p.x) - std::abs(p.y)), p.y};
}

double triangleSolidAngle(glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) {
  const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
  const double num = std::abs(glm::dot(a, glm::cross(b, c)));
  const double den = la * lb * lc + glm::dot(a, b) * lc + glm::dot(a, c) * lb + glm::dot(b, c) * la;
  return 2.0 * std::atan2(num, den);
}

}  // namespace

std::vector<double> hemiOctTexelSolidAngles(int size) {
  NL_CHECK(size > 0);
  std::vector<double> omega(size_t(size) * size, 0.0);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      Polygon texel;
      for (glm::dvec2 t : {glm::dvec2(x, y), glm::dvec2(x + 1, y), glm::dvec2(x + 1, y + 1),
                           glm::dvec2(x, y + 1)}) {
        t /= double(size);
        texel.push_back({1.0 - t.x - t.y, t.x - t.y});  // eq. 2 inverted: (x, z)
      }
      double sum = 0;
      for (double sx : {1.0, -1.0})
        for (double sz : {1.0, -1.0}) {
          const Polygon piece = clip(clip(texel, 0, sx), 1, sz);
          for (size_t k = 1; k + 1 < piece.size(); ++k)
            sum += triangleSolidAngle(lift(piece[0]), lift(piece[k]), lift(piece[k + 1]));
        }
      omega[size_t(y) * size + x] = sum;
    }
  return omega;
}

}  // namespace nestlight::gi::projection
