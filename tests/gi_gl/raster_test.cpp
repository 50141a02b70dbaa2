// The `raster` method (GI frame, GL): closed forms for a point light and a spot over a plane, a
// shadow's umbra, agreement with the reference's `direct` on a generated scene, tiles, OSMesa.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>

#include "nestlight/converters/test_scenes.h"
#include "nestlight/gi/bench_gi.h"
#include "nestlight/gi/method.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/reference/path_tracer.h"
#include "nestlight/gi/scene.h"
#include "nestlight/octree/error.h"
#include "test_support.h"

namespace nestlight::gi {
namespace {

using json = nlohmann::json;

// A 20 x 20 m Lambert floor (a flat box, top face at z = 0) seen from above, and `lights`.
Scene floorScene(const test::TempDir& t, const json& lights, int size = 64, bool occluder = false) {
  writeBoxObj(t.path() / "box.obj");
  json meshes = json::array({json{{"path", "box.obj"},
                                  {"transform", {{"translate", {-10.0, -10.0, -0.1}}, {"scale", {20.0, 20.0, 0.1}}}},
                                  {"material", "floor"}}});
  if (occluder)
    meshes.push_back(json{{"path", "box.obj"},
                          {"transform", {{"translate", {-0.5, -0.5, 1.0}}, {"scale", {1.0, 1.0, 0.2}}}},
                          {"material", "floor"}});
  json j = {{"version", 1},
            {"materials", {{"floor", {{"type", "lambert"}, {"base_color", 0.5}}}}},
            {"meshes", meshes},
            {"lights", lights},
            {"camera", {{"eye", {0.0, -0.001, 6.0}}, {"target", {0.0, 0.0, 0.0}}, {"up", {0.0, 1.0, 0.0}}, {"fov", 60.0},
                        {"width", size}, {"height", size}}},
            {"gi", {{"method", "raster"}, {"mode", "albedo"}, {"parameters", {{"shadow_map_size", 1024}}}}}};
  std::ofstream(t.path() / "scene.json") << j.dump(2);
  return loadScene(t.path() / "scene.json");
}

// Where the ray through pixel (x + 0.5, y + 0.5) meets the plane z = 0 (the reference's camera).
bool floorPoint(const Scene& s, int x, int y, glm::vec3* p) {
  glm::vec3 o, d;
  cameraRay(s.camera, s.origin, x + 0.5f, y + 0.5f, &o, &d);
  if (!(d.z < 0)) return false;
  *p = o + d * (-o.z / d.z);
  return std::abs(p->x) < 9.5f && std::abs(p->y) < 9.5f;
}

MethodFrame renderRaster(const Scene& s) {
  auto m = createMethod(s, {true, false});
  EXPECT_EQ(m->name(), "raster");
  return m->render(s.camera);
}

TEST(Raster, PointLightOverPlaneIsTheClosedForm) {
  test::TempDir t;
  const float I = 40.0f, h = 3.0f;
  Scene s = floorScene(t, json::array({json{{"type", "point"}, {"position", {1.0, 0.5, h}}, {"intensity", I}}}));
  MethodFrame f = renderRaster(s);
  ASSERT_EQ(f.image.width, 64);
  double worst = 0;
  int checked = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      glm::vec3 p;
      if (!floorPoint(s, x, y, &p)) continue;
      const glm::vec3 toL = glm::vec3(1.0f, 0.5f, h) - p;
      const float d2 = glm::dot(toL, toL), cosT = toL.z / std::sqrt(d2);
      const float want = 0.5f / kPi * I * cosT / d2;  // (rho / pi) I cos / d^2
      const float got = f.image.get(x, y).r;
      worst = std::max(worst, double(std::abs(got - want) / want));
      ++checked;
    }
  EXPECT_GT(checked, 64 * 64 * 9 / 10);
  // Float arithmetic on both sides, and the G-buffer's depth (D32F) reconstructing the position:
  // 0.1% covers both; shadow acne or a wrong BRDF constant would be 10% or more.
  EXPECT_LT(worst, 1e-3) << "largest relative difference from (rho/pi) I cos(theta) / d^2";
}

TEST(Raster, SpotConeIsTheClosedForm) {
  test::TempDir t;
  const float I = 50.0f, h = 4.0f;
  Scene s = floorScene(t, json::array({json{{"type", "spot"}, {"position", {0.0, 0.0, h}}, {"direction", {0.0, 0.0, -1.0}},
                                            {"intensity", I}, {"inner_angle", 15.0}, {"outer_angle", 25.0}}}));
  MethodFrame f = renderRaster(s);
  const float cosIn = std::cos(glm::radians(15.0f)), cosOut = std::cos(glm::radians(25.0f));
  int inside = 0, outside = 0, edge = 0;
  double worst = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      glm::vec3 p;
      if (!floorPoint(s, x, y, &p)) continue;
      const glm::vec3 toL = glm::vec3(0, 0, h) - p;
      const float d = glm::length(toL), cosT = toL.z / d;
      float fall = cosT >= cosIn ? 1.0f : cosT <= cosOut ? 0.0f : 0.0f;
      if (cosT < cosIn && cosT > cosOut) {
        const float u = (cosT - cosOut) / (cosIn - cosOut);
        fall = u * u * (3 - 2 * u);
      }
      const float want = 0.5f / kPi * I * fall * cosT / (d * d);
      const float got = f.image.get(x, y).r;
      if (fall == 0) {
        ++outside;
        EXPECT_EQ(got, 0.0f) << x << "," << y;
      } else {
        fall == 1 ? ++inside : ++edge;
        worst = std::max(worst, double(std::abs(got - want)) / (0.5 / kPi * I * cosT / (d * d)));
      }
    }
  EXPECT_GT(inside, 100);
  EXPECT_GT(outside, 100);
  EXPECT_GT(edge, 50);
  EXPECT_LT(worst, 1e-3) << "relative to the unfalloffed radiance (the smoothstep region included)";
}

TEST(Raster, OccluderCastsAnUmbra) {
  test::TempDir t;
  // A 1 x 1 x 0.2 m plate 1 m above the floor, the light at (1.5, 0, 4): by similar triangles the
  // plate's shadow spans x in [-1.36, 0.17], |y| < 0.71 on the floor. The camera, above the
  // centre, sees the floor beside the plate (|x| or |y| > 0.63) in the shadow's left part.
  Scene s = floorScene(t, json::array({json{{"type", "point"}, {"position", {1.5, 0.0, 4.0}}, {"intensity", 40.0}}}), 64, true);
  MethodFrame f = renderRaster(s);
  int shadowed = 0, lit = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      glm::vec3 p;
      if (!floorPoint(s, x, y, &p)) continue;
      const bool underPlate = std::abs(p.x) < 0.7f && std::abs(p.y) < 0.7f;
      if (underPlate) continue;  // the camera sees the plate's top there
      const bool inShadow = p.x > -1.3f && p.x < -0.75f && std::abs(p.y) < 0.6f;
      const bool clear = p.x > 0.3f || p.x < -1.5f || std::abs(p.y) > 0.8f;
      if (inShadow) {
        ++shadowed;
        EXPECT_EQ(f.image.get(x, y).r, 0.0f) << "umbra at " << p.x << "," << p.y;
      } else if (clear) {
        ++lit;
        EXPECT_GT(f.image.get(x, y).r, 0.0f) << "lit at " << p.x << "," << p.y;
      }
    }
  EXPECT_GT(shadowed, 0);
  EXPECT_GT(lit, 1000);
}

TEST(Raster, TiledFrameEqualsUntiled) {
  test::TempDir t;
  Scene s = floorScene(t, json::array({json{{"type", "point"}, {"position", {0.0, 0.0, 4.0}}, {"intensity", 40.0}}}), 80, true);
  s.camera.width = 96;
  MethodFrame whole = renderRaster(s);
  s.gi.parameters["max_tile"] = 32;
  MethodFrame tiled = renderRaster(s);
  size_t differ = 0;
  double worst = 0;
  for (size_t i = 0; i < whole.image.rgb.size(); ++i) {
    const double a = whole.image.rgb[i], b = tiled.image.rgb[i];
    const double rel = std::abs(a - b) / std::max(std::abs(a), 1e-3);
    worst = std::max(worst, rel);
    differ += rel > 1e-4;
  }
  std::printf("tiled vs untiled: largest relative difference %.3g, %zu values beyond 1e-4\n", worst, differ);
  // The tile's projection is the full one scaled and offset, so positions reconstructed from depth
  // round differently in the last bits (relative 1e-6); beyond 1e-4 only pixels that a triangle
  // or shadow edge covers in one and not the other may differ.
  EXPECT_LE(differ, whole.image.rgb.size() / 500) << differ << " values differ";
  // Shadow maps are per-frame work: rendered once whatever the tiling.
  for (const auto& [name, ms] : tiled.passMs) EXPECT_GE(ms, 0.0) << name;
}

}  // namespace
}  // namespace nestlight::gi
