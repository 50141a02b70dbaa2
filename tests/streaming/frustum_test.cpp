// Frustum culling against brute force: a box with a point inside the clip volume is never culled,
// and a box whose corners all lie beyond one clip plane always is.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>
#include <random>

#include "nestlight/streaming/view.h"

using namespace nestlight;
using namespace nestlight::streaming;

namespace {

bool insideClip(const glm::dmat4& m, const glm::dvec3& p) {
  const glm::dvec4 q = m * glm::dvec4(p, 1.0);
  return q.w > 0 && std::abs(q.x) <= q.w && std::abs(q.y) <= q.w && std::abs(q.z) <= q.w;
}

// Some point of a 9^3 grid over the box lies inside the clip volume.
bool someSampleInside(const glm::dmat4& m, const Box3d& b) {
  for (int i = 0; i <= 8; ++i)
    for (int j = 0; j <= 8; ++j)
      for (int k = 0; k <= 8; ++k) {
        const glm::dvec3 p(b.min.x + (b.max.x - b.min.x) * i / 8,
                           b.min.y + (b.max.y - b.min.y) * j / 8,
                           b.min.z + (b.max.z - b.min.z) * k / 8);
        if (insideClip(m, p)) return true;
      }
  return false;
}

// All eight corners lie beyond the same one of the six clip planes.
bool cornersBeyondOnePlane(const glm::dmat4& m, const Box3d& b) {
  for (int plane = 0; plane < 6; ++plane) {
    const int axis = plane / 2;
    const double sign = plane % 2 ? 1.0 : -1.0;
    bool all = true;
    for (int c = 0; c < 8 && all; ++c) {
      const glm::dvec4 q = m * glm::dvec4((c & 4) ? b.max.x : b.min.x, (c & 2) ? b.max.y : b.min.y,
                                          (c & 1) ? b.max.z : b.min.z, 1.0);
      all = sign * q[axis] > q.w;
    }
    if (all) return true;
  }
  return false;
}

void checkAgainstBruteForce(const glm::dvec3& origin, double extent, bool orthographic,
                            unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1), pos(0.02, 1);
  int inside = 0, culled = 0;
  for (int cam = 0; cam < 20; ++cam) {
    const glm::dvec3 eye = origin + extent * glm::dvec3(u(rng), u(rng), u(rng));
    const glm::dvec3 target = origin + extent * glm::dvec3(u(rng), u(rng), u(rng));
    const glm::dmat4 proj =
        orthographic ? glm::ortho(-extent / 3, extent / 3, -extent / 4, extent / 4, 0.0, 2 * extent)
                     : glm::perspective(glm::radians(20.0 + 70 * pos(rng)), 1.0 + pos(rng),
                                        0.01 * extent, 3 * extent);
    const glm::dmat4 m = proj * glm::lookAt(eye, target, glm::dvec3(0, 0, 1));
    const Frustum f(m);
    for (int i = 0; i < 300; ++i) {
      const glm::dvec3 c = origin + extent * glm::dvec3(u(rng), u(rng), u(rng));
      const glm::dvec3 h = 0.3 * extent * glm::dvec3(pos(rng), pos(rng), pos(rng)) * pos(rng);
      Box3d b;
      b.min = {c.x - h.x, c.y - h.y, c.z - h.z};
      b.max = {c.x + h.x, c.y + h.y, c.z + h.z};
      const bool hit = f.intersects(b);
      if (someSampleInside(m, b)) {
        ++inside;
        EXPECT_TRUE(hit) << "a visible box was culled";
      }
      if (cornersBeyondOnePlane(m, b)) {
        ++culled;
        EXPECT_FALSE(hit) << "a box beyond one plane was kept";
      }
    }
  }
  // Both cases occurred often enough to mean something.
  EXPECT_GT(inside, 300);
  EXPECT_GT(culled, 300);
}

}  // namespace

TEST(Frustum, PerspectiveAgreesWithBruteForce) {
  checkAgainstBruteForce({0, 0, 0}, 100, false, 1);
}
TEST(Frustum, OrthographicAgreesWithBruteForce) {
  checkAgainstBruteForce({0, 0, 0}, 100, true, 2);
}
TEST(Frustum, NationalGridAgreesWithBruteForce) {
  checkAgainstBruteForce({500000, 5000000, 100}, 50, false, 3);
}

TEST(Frustum, EmptyBoxIsNeverVisible) {
  const Frustum f(glm::perspective(1.0, 1.0, 0.1, 100.0));
  EXPECT_FALSE(f.intersects(Box3d{}));
}

TEST(View, PerspectiveViewPixelsPerUnit) {
  const View v =
      perspectiveView({0, 0, 0}, {0, 10, 0}, {0, 0, 1}, glm::radians(90.0), 800, 600, 0.1, 100);
  EXPECT_NEAR(v.pixelsPerUnit, 300.0, 1e-9);  // 600 / (2 tan 45)
  EXPECT_NEAR(v.projectedPixels(2.0, 10.0), 60.0, 1e-9);
  // The target projects to the centre of the image.
  const glm::dvec4 q = v.clipFromWorld * glm::dvec4(0, 10, 0, 1);
  EXPECT_NEAR(q.x / q.w, 0.0, 1e-12);
  EXPECT_NEAR(q.y / q.w, 0.0, 1e-12);
}
