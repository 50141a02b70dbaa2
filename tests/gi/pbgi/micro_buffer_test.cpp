// Micro-buffer geometry: the paraboloid map's round trip, and m-pixel solid angles that make the
// eq. 7 quadrature exact for a uniform hemisphere (sum 2 pi; cosine-weighted sum pi).
#include "nestlight/gi/pbgi/micro_buffer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace nestlight::gi::pbgi {
namespace {

TEST(MicroBuffer, ParaboloidRoundTrip) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(-1, 1);
  for (int i = 0; i < 10000; ++i) {
    glm::vec3 w(u(rng), u(rng), std::fabs(u(rng)));
    if (glm::length(w) < 1e-3f) continue;
    w = glm::normalize(w);
    const glm::vec2 st = paraboloidFromDirection(w);
    ASSERT_LE(glm::length(st), 1.0f + 1e-6f);
    const glm::vec3 back = directionFromParaboloid(st);
    ASSERT_NEAR(glm::length(back - w), 0.0f, 1e-5f);
  }
  EXPECT_NEAR(glm::length(directionFromParaboloid({0, 0}) - glm::vec3(0, 0, 1)), 0, 1e-7);
  EXPECT_NEAR(directionFromParaboloid({1, 0}).z, 0, 1e-7);  // the disc's rim is the horizon
}

// Tolerance: 16 x 16 sub-samples per m-pixel integrate the clipped rim squares to about 1e-3 of
// the total at M = 4 (the coarsest), better for finer maps.
TEST(MicroBuffer, SolidAnglesIntegrateTheHemisphere) {
  for (int m : {4, 8, 16, 32, 64}) {
    const MicroBufferTable t = microBufferTable(m);
    EXPECT_NEAR(t.solidAngleSum(), 2 * M_PI, 2 * M_PI * 2e-3) << m;
    EXPECT_NEAR(t.cosineWeightedSum(), M_PI, M_PI * 2e-3) << m;
    // Corners lie outside the disc (from 8 x 8 on: at 4 x 4 the corner square reaches into it);
    // the pole's m-pixels are the largest (4x the rim's per area).
    if (m >= 8) {
      EXPECT_EQ(t.texels[0].w, 0.0f);
    }
    const float pole = t.texels[size_t(m / 2) * m + m / 2].w;
    for (const auto& x : t.texels) {
      EXPECT_LE(x.w, pole * 1.0001f);
      EXPECT_LE(glm::length(glm::vec3(x)), 1.0f + 1e-6f);
      EXPECT_GE(x.z, 0.0f);
    }
    EXPECT_NEAR(mPixelSolidAngle(m) * m * m, 2 * M_PI, 1e-4);
  }
}

}  // namespace
}  // namespace nestlight::gi::pbgi
