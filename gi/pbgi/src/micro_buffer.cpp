#include "nestlight/gi/pbgi/micro_buffer.h"

#include <cmath>

#include "nestlight/octree/error.h"

namespace nestlight::gi::pbgi {

namespace {
constexpr double kTwoPi = 6.283185307179586;
}

glm::vec2 paraboloidFromDirection(const glm::vec3& w) {
  return glm::vec2(w.x, w.y) / (1.0f + w.z);
}

glm::vec3 directionFromParaboloid(const glm::vec2& st) {
  const float r2 = glm::dot(st, st);
  return glm::vec3(2.0f * st.x, 2.0f * st.y, 1.0f - r2) / (1.0f + r2);
}

MicroBufferTable microBufferTable(int size) {
  NL_CHECK(size >= 1 && size <= 1024);
  MicroBufferTable t;
  t.size = size;
  t.texels.assign(size_t(size) * size, glm::vec4(0));
  constexpr int kSub = 16;
  const double pixel = 2.0 / size, sub = pixel / kSub;
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) {
      glm::dvec3 dir(0);
      double omega = 0;
      for (int b = 0; b < kSub; ++b)
        for (int a = 0; a < kSub; ++a) {
          const double s = -1 + i * pixel + (a + 0.5) * sub, u = -1 + j * pixel + (b + 0.5) * sub;
          const double r2 = s * s + u * u;
          if (r2 > 1) continue;
          // d omega = 4 / (1 + r^2)^2 ds dt on the paraboloid map.
          const double dOmega = 4.0 / ((1 + r2) * (1 + r2)) * sub * sub;
          omega += dOmega;
          dir += dOmega * glm::dvec3(2 * s, 2 * u, 1 - r2) / (1 + r2);
        }
      if (omega > 0)
        t.texels[size_t(j) * size + i] = glm::vec4(glm::vec3(dir / omega), float(omega));
    }
  return t;
}

float MicroBufferTable::solidAngleSum() const {
  double s = 0;
  for (const auto& x : texels) s += x.w;
  return float(s);
}

float MicroBufferTable::cosineWeightedSum() const {
  double s = 0;
  for (const auto& x : texels) s += double(x.w) * x.z;
  return float(s);
}

float mPixelSolidAngle(int size) {
  return float(kTwoPi / (double(size) * size));
}

}  // namespace nestlight::gi::pbgi
