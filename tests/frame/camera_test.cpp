// The viewer's camera control keeps a scene camera's up: it opens on the camera as given and
// turns about that up (the viewer assumed z-up and dropped it).
#include "nestlight/frame/camera.h"

#include <gtest/gtest.h>

#include <glm/glm.hpp>

using namespace nestlight::frame;

namespace {

void expectNear(const glm::dvec3& a, const glm::dvec3& b, double tol) {
  EXPECT_NEAR(glm::length(a - b), 0.0, tol)
      << a.x << " " << a.y << " " << a.z << " vs " << b.x << " " << b.y << " " << b.z;
}

}  // namespace

TEST(CameraController, OpensOnTheCameraAsGivenWhateverItsUp) {
  for (const glm::dvec3 up : {glm::dvec3(0, 0, 1), glm::dvec3(0, 1, 0), glm::dvec3(1, 0, 0),
                              glm::dvec3(0.3, -0.5, 0.8), glm::dvec3(0, 0, -1)}) {
    Camera c;
    c.eye = {3, -2, 5};
    c.target = {0.5, 1, -1};
    c.up = up;
    c.fovYDegrees = 40;
    CameraController cc;
    cc.from(c);
    const Camera back = cc.camera();
    expectNear(back.eye, c.eye, 1e-9);
    expectNear(back.target, c.target, 1e-12);
    expectNear(back.up, glm::normalize(up), 1e-12);
    EXPECT_EQ(back.fovYDegrees, 40);
    // Yaw turns about that up: the eye's height along it and its distance stay, it moves.
    cc.yaw += 90;
    const Camera turned = cc.camera();
    EXPECT_NEAR(glm::dot(turned.eye - c.target, glm::normalize(up)),
                glm::dot(c.eye - c.target, glm::normalize(up)), 1e-9);
    EXPECT_NEAR(glm::length(turned.eye - c.target), glm::length(c.eye - c.target), 1e-9);
    EXPECT_GT(glm::length(turned.eye - c.eye), 1.0);
  }
}

TEST(CameraController, ZUpTurnsAsTheViewerAlwaysDid) {
  Camera c;
  c.eye = {1, 0, 0};
  c.target = {0, 0, 0};
  CameraController cc;
  cc.from(c);
  EXPECT_NEAR(cc.yaw, 0, 1e-12);
  EXPECT_NEAR(cc.pitch, 0, 1e-12);
  cc.yaw = 90;
  expectNear(cc.camera().eye, {0, 1, 0}, 1e-12);  // yaw 90 looks from +y
  cc.pitch = 90;
  expectNear(cc.camera().eye, {0, 0, 1}, 1e-12);
  // A degenerate up falls back to z.
  c.up = {0, 0, 0};
  cc.from(c);
  expectNear(cc.up, {0, 0, 1}, 0);
}
