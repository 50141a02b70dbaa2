// Order-2 SH irradiance of a lat-long map (Ramamoorthi and Hanrahan 2001, "An Efficient
// Representation for Irradiance Environment Maps", eq. 10-12;
// nestlight/gi/frame/irradiance_sh.h).
#include "nestlight/gi/frame/irradiance_sh.h"

#include <algorithm>
#include <cmath>

namespace nestlight::gi {

namespace {
constexpr double kPiD = 3.14159265358979323846;
}  // namespace

std::array<glm::vec3, 9> irradianceSh(const EnvironmentMap& env) {
  std::array<glm::dvec3, 9> L{};
  const HdrImage& img = env.image();
  const double rot = double(env.rotationDegrees()) * kPiD / 180;
  // Each texel is integrated over its own area: sub-samples make the quadrature at least 128 x 64
  // (a constant sky is one texel, which a single sample would put all on the equator's -x
  // point: irradiance 6.7 times too high on a face looking that way), each weighted by its
  // exact solid angle (cos theta0 - cos theta1) dphi.
  const int sx = std::max(1, (128 + img.width - 1) / img.width),
            sy = std::max(1, (64 + img.height - 1) / img.height);
  const int W = img.width * sx, H = img.height * sy;
  for (int y = 0; y < H; ++y) {
    const double t0 = kPiD * y / H, t1 = kPiD * (y + 1) / H, theta = 0.5 * (t0 + t1);
    const double dOmega = (2 * kPiD / W) * (std::cos(t0) - std::cos(t1));
    for (int x = 0; x < W; ++x) {
      const double phi = 2 * kPiD * (x + 0.5) / W + rot;
      const double dx = std::sin(theta) * std::cos(phi), dy = std::sin(theta) * std::sin(phi),
                   dz = std::cos(theta);
      const Rgb c = img.get(x / sx, y / sy);
      const glm::dvec3 v = glm::dvec3(c.r, c.g, c.b) * double(env.scale()) * dOmega;
      if (!std::isfinite(v.x + v.y + v.z)) continue;
      const double Y[9] = {0.282095,
                           0.488603 * dy,
                           0.488603 * dz,
                           0.488603 * dx,
                           1.092548 * dx * dy,
                           1.092548 * dy * dz,
                           0.315392 * (3 * dz * dz - 1),
                           1.092548 * dx * dz,
                           0.546274 * (dx * dx - dy * dy)};
      for (int k = 0; k < 9; ++k) L[k] += v * Y[k];
    }
  }
  const double A[9] = {kPiD,     2 * kPiD / 3, 2 * kPiD / 3, 2 * kPiD / 3, kPiD / 4,
                       kPiD / 4, kPiD / 4,     kPiD / 4,     kPiD / 4};
  const double C[9] = {0.282095, 0.488603, 0.488603, 0.488603, 1.092548,
                       1.092548, 0.315392, 1.092548, 0.546274};
  std::array<glm::vec3, 9> out;
  for (int k = 0; k < 9; ++k) out[k] = glm::vec3(L[k] * A[k] * C[k]);
  return out;
}

}  // namespace nestlight::gi
