// The `raster` method (GI frame, GL): closed forms for a point light and a spot over a plane, a
// shadow's umbra, agreement with the reference's `direct` on a generated scene, tiles, OSMesa.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <set>
#include <vector>

#include "gi/floor_scene.h"
#include "nestlight/converters/builder.h"
#include "nestlight/converters/reader.h"
#include "nestlight/converters/test_scenes.h"
#include "nestlight/gi/frame/shadow_fit.h"
#include "nestlight/gi/method.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/metrics.h"
#include "nestlight/gi/reference/path_tracer.h"
#include "nestlight/gi/scene.h"
#include "nestlight/gi/srgb.h"
#include "nestlight/gi/tone_map.h"
#include "nestlight/gl/context.h"
#include "nestlight/octree/error.h"
#include "test_support.h"

namespace nestlight::gi {
namespace {

using json = nlohmann::json;

MethodFrame renderRaster(const Scene& s) {
  auto m = createMethod(s, {true, false});
  EXPECT_EQ(m->name(), "raster");
  return m->render(s.camera);
}

TEST(Raster, PointLightOverPlaneIsTheClosedForm) {
  test::TempDir t;
  const float I = 40.0f, h = 3.0f;
  Scene s = lambertFloorScene(
      t, json::array({json{{"type", "point"}, {"position", {1.0, 0.5, h}}, {"intensity", I}}}));
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
  Scene s = lambertFloorScene(t, json::array({json{{"type", "spot"},
                                                   {"position", {0.0, 0.0, h}},
                                                   {"direction", {0.0, 0.0, -1.0}},
                                                   {"intensity", I},
                                                   {"inner_angle", 15.0},
                                                   {"outer_angle", 25.0}}}));
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
  Scene s = lambertFloorScene(
      t, json::array({json{{"type", "point"}, {"position", {1.5, 0.0, 4.0}}, {"intensity", 40.0}}}),
      64, true);
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
  Scene s = lambertFloorScene(
      t, json::array({json{{"type", "point"}, {"position", {0.0, 0.0, 4.0}}, {"intensity", 40.0}}}),
      80, true);
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
  std::printf("tiled vs untiled: largest relative difference %.3g, %zu values beyond 1e-4\n", worst,
              differ);
  // The tile's projection is the full one scaled and offset, so positions reconstructed from depth
  // round differently in the last bits (relative 1e-6); beyond 1e-4 only pixels that a triangle
  // or shadow edge covers in one and not the other may differ.
  EXPECT_LE(differ, whole.image.rgb.size() / 500) << differ << " values differ";
  // Shadow maps are per-frame work: rendered once whatever the tiling; tile passes sum over the
  // tiles into one entry. Both frames list the same passes, each once.
  std::vector<std::string> tiledNames, wholeNames;
  for (const auto& [name, ms] : tiled.passMs) tiledNames.push_back(name);
  for (const auto& [name, ms] : whole.passMs) wholeNames.push_back(name);
  std::sort(tiledNames.begin(), tiledNames.end());
  std::sort(wholeNames.begin(), wholeNames.end());
  EXPECT_EQ(tiledNames, wholeNames);
  EXPECT_EQ(std::adjacent_find(tiledNames.begin(), tiledNames.end()), tiledNames.end())
      << "a pass listed twice";
  EXPECT_NE(std::find(tiledNames.begin(), tiledNames.end(), "shadow_maps"), tiledNames.end());
}

// The same with a scan: splats that straddle a tile border are drawn in both tiles (the guard
// band), and the pin-hole fill and high-quality splatting see the same neighbours.
TEST(Raster, TiledScanFrameEqualsUntiled) {
  test::TempDir t;
  TestSceneOptions so;
  so.points = 60'000;
  so.width = 96;
  so.height = 72;
  so.quiet = true;
  Scene s = loadScene(makeTestScene(TestSceneKind::Cornell, t.file("c"), so));
  s.gi.method = "raster";
  s.gi.mode = RadianceMode::Albedo;
  for (const char* splatting : {"hqs", "basic"}) {
    s.gi.parameters = json{{"splatting", splatting}};
    MethodFrame whole = renderRaster(s);
    s.gi.parameters["max_tile"] = 32;
    MethodFrame tiled = renderRaster(s);
    size_t differ = 0;
    for (size_t i = 0; i < whole.image.rgb.size(); ++i) {
      const double a = whole.image.rgb[i], b = tiled.image.rgb[i];
      differ += std::abs(a - b) > 0.02 * std::max(std::abs(a), 0.01);
    }
    if (const char* keep = std::getenv("NESTLIGHT_TEST_KEEP")) {
      writeToneMappedPng(std::string(keep) + "/tile_whole_" + splatting + ".png", whole.image, 0);
      writeToneMappedPng(std::string(keep) + "/tile_tiled_" + splatting + ".png", tiled.image, 0);
    }
    std::printf("%s: tiled vs untiled scan frame, %zu of %zu values beyond 2%%\n", splatting,
                differ, whole.image.rgb.size());
    // Positions reconstructed under the tile's projection differ in their last bits, which moves
    // soft shadow edges (PCF) by far less than 1%; and llvmpipe rasterises a splat's rim in fixed
    // point relative to the viewport, so a few rim pixels flip between nearest splats. A seam
    // along a tile border would be hundreds of values here.
    EXPECT_LE(differ, whole.image.rgb.size() / 50) << splatting;  // measured: basic 0.5%, hqs 0.4%
  }
}

// The make-scene scenes, raster against the reference's first bounce in the albedo mode (the scan
// lit by the scene's lights, as the raster method lights it).
struct Agreement {
  double relativeL2 = 0;   // over all pixels
  double energyRatio = 0;  // sum raster / sum direct
  double within25 = 0;  // share of pixels within 25% (relative to the pixel, floor 5% of the mean)
  double blockLo = INFINITY, blockHi = 0;  // raster / direct over 8 x 8 pixel blocks (lit blocks)
};

Agreement rasterAgainstDirect(TestSceneKind kind, bool dropEnvironment, const std::string& dir) {
  TestSceneOptions so;
  so.points = 120'000;
  so.width = 64;
  so.height = 48;
  so.quiet = true;
  const auto file = makeTestScene(kind, dir, so);
  Scene s = loadScene(file);
  s.gi.mode = RadianceMode::Albedo;
  if (dropEnvironment) s.environment.reset();
  s.gi.method = "direct";
  s.gi.samplesPerPixel = 256;
  s.gi.targetRelativeError = 0;
  MethodFrame ref = createMethod(s, {true, false})->render(s.camera);
  s.gi.method = "raster";
  MethodFrame ras = createMethod(s, {true, false})->render(s.camera);
  Agreement a;
  a.relativeL2 = relativeL2(ras.image, ref.image);
  double sr = 0, sd = 0;
  for (size_t i = 0; i < ref.image.rgb.size(); ++i) sr += ras.image.rgb[i], sd += ref.image.rgb[i];
  a.energyRatio = sr / sd;
  const double floor = 0.05 * sd / double(ref.image.rgb.size());
  size_t good = 0;
  for (size_t p = 0; p < ref.image.pixels(); ++p) {
    const double r = luminance(ras.image.get(int(p % ref.image.width), int(p / ref.image.width)));
    const double d = luminance(ref.image.get(int(p % ref.image.width), int(p / ref.image.width)));
    good += std::abs(r - d) <= 0.25 * std::max(d, floor);
  }
  a.within25 = double(good) / double(ref.image.pixels());
  const double meanLum = sd / double(ref.image.rgb.size());
  for (int by = 0; by + 8 <= ref.image.height; by += 8)
    for (int bx = 0; bx + 8 <= ref.image.width; bx += 8) {
      double r = 0, d = 0;
      for (int y = by; y < by + 8; ++y)
        for (int x = bx; x < bx + 8; ++x)
          r += luminance(ras.image.get(x, y)), d += luminance(ref.image.get(x, y));
      if (d < 0.2 * meanLum * 64) continue;  // a dark block's ratio is mostly noise
      a.blockLo = std::min(a.blockLo, r / d);
      a.blockHi = std::max(a.blockHi, r / d);
    }
  std::printf(
      "%s: raster against direct (256 spp, its own error %.4f): relative L2 %.4f, energy ratio "
      "%.4f, "
      "%.1f%% of pixels within 25%%, 8x8 blocks %.2f to %.2f\n",
      testSceneKindName(kind), ref.relativeError, a.relativeL2, a.energyRatio, 100 * a.within25,
      a.blockLo, a.blockHi);
  if (const char* keep = std::getenv("NESTLIGHT_TEST_KEEP")) {
    writeToneMappedPng(std::string(keep) + "/" + testSceneKindName(kind) + "_raster.png", ras.image,
                       0);
    writeToneMappedPng(std::string(keep) + "/" + testSceneKindName(kind) + "_direct.png", ref.image,
                       0);
  }
  return a;
}

TEST(Raster, AgreesWithDirectOnGeneratedScenes) {
  test::TempDir t;
  // Measured on llvmpipe at 64 x 48 (docs/SCENE.md, "raster against direct"), high-quality
  // splatting: cornell energy ratio 1.07, lit 8 x 8 blocks 0.89 to 1.29; object 0.95. Since the
  // reference's discs close the surface (no ray leaves the room): cornell energy ratio 1.006,
  // blocks 0.64 to 1.46 (the spread of single blocks grew with the wider discs; not diagnosed
  // further), object 0.93. Per pixel
  // they differ more (relative L2 0.24 and 0.95): the reference averages each pixel's area where
  // raster blends the splats at its centre (the
  // scans' colour is noisy per point), and edges of splats and discs fall differently. What makes
  // the blocks differ: raster's shadow lookups move off the surface by a splat radius, removing
  // self-shadowing of relief finer than a splat; raster reconstructs a splat's
  // pixels at the splat centre's depth (measured on a scanned plane seen at 50 degrees: raster
  // 0.97 to 1.03 of the closed form, direct 0.94 to 0.99). A wrong light unit, a missing cosine
  // or shadow acne gives ratios of 0.3 or 3.
  const Agreement c = rasterAgainstDirect(TestSceneKind::Cornell, false, t.file("cornell"));
  EXPECT_NEAR(c.energyRatio, 1.0, 0.1);
  EXPECT_GT(c.blockLo, 0.55);
  EXPECT_LT(c.blockHi, 1.6);
  // The object scene's sky lights surfaces unoccluded in raster (spherical harmonics) and
  // occluded in the reference: compared without it. Its town scan is coarse (120k points over
  // 100 m), so only the totals are compared.
  const Agreement o = rasterAgainstDirect(TestSceneKind::Object, true, t.file("object"));
  EXPECT_NEAR(o.energyRatio, 1.0, 0.15);
}

// A scanned plane of one colour under a point light: scan points in the albedo mode are Lambert
// reflectors of their colour, so the raster method (splats into the G-buffer) and the reference's
// `direct` (discs) must both give (rho / pi) I cos(theta) / d^2 across the plane.
TEST(Raster, ScannedPlaneUnderAPointLightIsTheClosedForm) {
  test::TempDir t;
  {
    std::ofstream ply(t.file("plane.ply"));
    ply << "ply\nformat ascii 1.0\nelement vertex 120000\nproperty float x\nproperty float "
           "y\nproperty float z\n"
           "property float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nproperty "
           "uchar green\n"
           "property uchar blue\nend_header\n";
    Rng rng(7);
    for (int i = 0; i < 120000; ++i)
      ply << rng.uniform() * 8 - 4 << " " << rng.uniform() * 8 - 4 << " 0 0 0 1 188 188 188\n";
  }
  test::buildOctreeFrom(t.file("plane.ply"), t.path() / "plane.octree");
  const float I = 40.0f;
  const glm::vec3 light(0.5f, 0.3f, 3.0f);
  json j = {{"version", 1},
            {"octrees", {{{"path", "plane.octree"}}}},
            {"lights",
             {{{"type", "point"}, {"position", {light.x, light.y, light.z}}, {"intensity", I}}}},
            {"camera",
             {{"eye", {0.0, -0.001, 6.0}},
              {"target", {0.0, 0.0, 0.0}},
              {"up", {0.0, 1.0, 0.0}},
              {"fov", 40.0},
              {"width", 48},
              {"height", 48}}},
            {"gi", {{"method", "raster"}, {"mode", "albedo"}, {"samples_per_pixel", 64}}}};
  std::ofstream(t.file("scene.json")) << j.dump();
  Scene s = loadScene(t.file("scene.json"));
  const float rho = srgbDecode(188.0f / 255.0f);
  // Both rasterisers fill the G-buffer: GL_POINTS splats (blended, or the nearest) and the
  // compute rasteriser.
  for (const char* method : {"raster", "raster-basic", "raster-compute", "direct"}) {
    s.gi.method = std::string(method).substr(0, std::string(method).find('-'));
    s.gi.parameters = json::object();
    if (std::string(method) == "raster-compute") s.gi.parameters["rasteriser"] = "compute";
    if (std::string(method) == "raster-basic") s.gi.parameters["splatting"] = "basic";
    MethodFrame f = createMethod(s, {true, false})->render(s.camera);
    double sum = 0, sumWant = 0;
    int n = 0;
    for (int y = 4; y < 44; ++y)
      for (int x = 4; x < 44; ++x) {
        glm::vec3 p;
        if (!floorPoint(s, x, y, &p)) continue;
        const glm::vec3 toL = light - p;
        const float d2 = glm::dot(toL, toL);
        sum += f.image.get(x, y).r;
        sumWant += rho / kPi * I * (toL.z / std::sqrt(d2)) / d2;
        ++n;
      }
    std::printf("%s: scanned plane, mean radiance / closed form = %.4f over %d pixels\n", method,
                sum / sumWant, n);
    EXPECT_NEAR(sum / sumWant, 1.0, 0.01) << method;
  }
}

// A scanned plate above a scanned floor, the camera under the plate looking down at its shadow's
// edge: the plate is out of the camera's view. The lights draw their own cut of the whole scan (at
// a shadow map's resolution), so the plate's shadow is there and its edge where the geometry puts
// it. (In a scan this small the camera's cut still holds the plate's coarse nodes, whose cubes
// reach into the view; in a large scan they would not, and without the lights' cut an out-of-view
// occluder would cast no shadow, or a blurred one from the coarsest levels.)
TEST(Raster, OccludersOutOfViewStillCastShadows) {
  test::TempDir t;
  {
    std::ofstream ply(t.file("s.ply"));
    const int floor = 60000, plate = 20000;
    ply << "ply\nformat ascii 1.0\nelement vertex " << floor + plate
        << "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty "
           "float ny\n"
           "property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar "
           "blue\nend_header\n";
    Rng rng(3);
    for (int i = 0; i < floor; ++i)
      ply << rng.uniform() * 8 - 4 << " " << rng.uniform() * 8 - 1 << " 0 0 0 1 188 188 188\n";
    for (int i = 0; i < plate; ++i)
      ply << rng.uniform() * 1.6 - 0.8 << " " << rng.uniform() * 1.6 + 2.2
          << " 1.5 0 0 1 188 188 188\n";
  }
  test::buildOctreeFrom(t.file("s.ply"), t.path() / "s.octree");
  json j = {{"version", 1},
            {"origin", {0.0, 0.0, 0.0}},  // world = local, as floorPoint() assumes
            {"octrees", {{{"path", "s.octree"}}}},
            {"lights", {{{"type", "point"}, {"position", {0.0, 3.0, 4.0}}, {"intensity", 40.0}}}},
            {"camera",
             {{"eye", {1.28, 2.999, 1.0}},
              {"target", {1.28, 3.0, 0.0}},
              {"up", {0.0, 1.0, 0.0}},
              {"fov", 40.0},
              {"width", 32},
              {"height", 32}}},
            {"gi", {{"method", "raster"}, {"mode", "albedo"}}}};
  std::ofstream(t.file("scene.json")) << j.dump();
  Scene s = loadScene(t.file("scene.json"));
  MethodFrame f = renderRaster(s);
  if (const char* keep = std::getenv("NESTLIGHT_TEST_KEEP"))
    writeToneMappedPng(std::string(keep) + "/outofview.png", f.image, 0);
  // The plate's edge x = 0.8 at z = 1.5 casts the shadow's edge at x = 0.8 x 4 / 2.5 = 1.28.
  const float rho = srgbDecode(188.0f / 255.0f);
  int inside = 0, outside = 0, litOk = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      glm::vec3 p;
      if (!floorPoint(s, x, y, &p)) continue;
      const glm::vec3 toL = glm::vec3(0.0f, 3.0f, 4.0f) - p;
      const float d2 = glm::dot(toL, toL), lit = rho / kPi * 40.0f * (toL.z / std::sqrt(d2)) / d2;
      const float got = f.image.get(x, y).r;
      if (p.x < 1.18f) {
        ++inside;
        EXPECT_LT(got, 0.05f * lit) << "umbra at x = " << p.x;
      } else if (p.x > 1.38f) {
        ++outside;
        litOk += got > 0.9f * lit;
      }
    }
  EXPECT_GT(inside, 100);
  EXPECT_GT(outside, 100);
  // A few single pixels of the lit floor are dark: gaps between the random floor's splats wider
  // than the pin-hole fill closes (measured: 6 of about 260).
  EXPECT_GE(litOk, outside * 95 / 100);
}

TEST(Raster, RunsOnTheOsMesaFallback) {
  test::TempDir t;
  Scene s = lambertFloorScene(t,
                              json::array({json{{"type", "spot"},
                                                {"position", {0.0, 0.0, 4.0}},
                                                {"direction", {0.0, 0.0, -1.0}},
                                                {"intensity", 50.0}}}),
                              32, true);
  if (!gl::createHeadlessContext()->isSoftware())
    GTEST_SKIP() << "EGL runs on a GPU here: the images of two rasterisers are not compared "
                    "value for value";
  MethodFrame egl = renderRaster(s);
  ::setenv("NESTLIGHT_GL_PLATFORM", "osmesa", 1);
  MethodFrame osmesa;
  try {
    osmesa = renderRaster(s);
  } catch (const Error& e) {
    ::unsetenv("NESTLIGHT_GL_PLATFORM");
    if (std::string(e.what()).find("libOSMesa is not installed") != std::string::npos)
      GTEST_SKIP() << "no OSMesa on this machine: " << e.what();
    throw;
  }
  ::unsetenv("NESTLIGHT_GL_PLATFORM");
  // The same Mesa rasteriser behind both: the same image, every GL function of a library outside
  // the viewer (frame, raster) resolved through OSMesa's table.
  ASSERT_EQ(osmesa.image.rgb.size(), egl.image.rgb.size());
  for (size_t i = 0; i < egl.image.rgb.size(); ++i)
    ASSERT_NEAR(osmesa.image.rgb[i], egl.image.rgb[i], 1e-5f) << i;
  double sum = 0;
  for (float v : osmesa.image.rgb) sum += v;
  EXPECT_GT(sum, 0);
}

// A mesh far from the scan must not clip the scan: the near plane follows the nearest object,
// not 1e-4 of the farthest (a torus 1000 km away put it 100 m out: a black image, exit 0).
TEST(Raster, AFarMeshDoesNotClipTheScan) {
  test::TempDir t;
  TestSceneOptions o;
  o.points = 20000;
  o.width = 48;
  o.height = 32;
  o.quiet = true;
  const auto file = makeTestScene(TestSceneKind::Object, t.path() / "town", o);
  nlohmann::json scene = nlohmann::json::parse(std::ifstream(file));
  nlohmann::json far = scene["meshes"][0];
  far["transform"]["translate"] = {1.0e6 + 50, 45.0, 5.0};
  scene["meshes"].push_back(far);
  std::ofstream(t.file("town/far.json")) << scene.dump(1);
  double mean[2];
  int k = 0;
  for (const char* name : {"scene.json", "far.json"}) {
    Scene s = loadScene(t.path() / "town" / name);
    s.gi.method = "raster";
    auto ctx = gl::createHeadlessContext();
    auto m = createMethod(s, {true, false});
    const MethodFrame f = m->render(s.camera);
    double sum = 0;
    for (float v : f.image.rgb) sum += v;
    mean[k++] = sum / double(f.image.rgb.size());
    EXPECT_EQ(f.attributes.at("nestlight:points"), "20000") << name;
  }
  // The image is the town's all the same, not black (its directional shadows stay as sharp too:
  // Raster.AFarMeshLeavesDirectionalShadowsAsTheyWere).
  EXPECT_GT(mean[1], 0.5 * mean[0]);
  EXPECT_LT(mean[1], 2.0 * mean[0]);
}

// A plate 1 m above the floor under a sun travelling along (-1, 0, -1): its shadow spans
// x in [-1.7, -0.5], |y| < 0.5 on the floor, and the camera above the centre sees its part beyond
// the plate (x < -0.63). Rendered alone and with a 20 m box 1000 km away, out of view: the
// directional shadow map covers what the camera sees (and the casters over it), so the far box
// changes nothing. Spanning the scene's bounds, the map's texels were 2 km wide with the far box
// and the umbra vanished (the lookup's normal offset alone, half a texel, lifted the floor above
// the plate).
TEST(Raster, AFarMeshLeavesDirectionalShadowsAsTheyWere) {
  test::TempDir t;
  json j = floorSceneJson(t, 64);
  const float E = 2.0f;
  addPlateUnderSun(j, E, false);
  j["gi"] = {{"method", "raster"}, {"mode", "albedo"}, {"parameters", {{"shadow_map_size", 512}}}};
  std::ofstream(t.file("near.json")) << j.dump(1);
  j["meshes"].push_back(farBox());
  std::ofstream(t.file("far.json")) << j.dump(1);
  const float lit = 0.5f / kPi * E * std::sqrt(0.5f);  // (rho / pi) E cos 45
  MethodFrame f[2];
  std::vector<int> dark[2];
  for (int k = 0; k < 2; ++k) {
    Scene s = loadScene(t.file(k ? "far.json" : "near.json"));
    f[k] = renderRaster(s);
    if (const char* keep = std::getenv("NESTLIGHT_TEST_KEEP"))
      writeToneMappedPng(std::string(keep) + (k ? "/sun_far.png" : "/sun_near.png"), f[k].image, 0);
    int umbra = 0, clear = 0;
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) {
        glm::vec3 p;
        if (!floorPoint(s, x, y, &p) || (std::abs(p.x) < 0.7f && std::abs(p.y) < 0.7f)) {
          dark[k].push_back(-1);  // not the floor, or under the plate as the camera sees it
          continue;
        }
        const float got = f[k].image.get(x, y).r;
        dark[k].push_back(got < 0.5f * lit);
        if (p.x > -1.6f && p.x < -0.75f && std::abs(p.y) < 0.4f) {
          ++umbra;
          EXPECT_LT(got, 0.05f * lit) << (k ? "far" : "near") << ": umbra at " << p.x << "," << p.y;
        } else if (p.x > 0.75f || p.x < -1.85f || std::abs(p.y) > 0.65f) {
          ++clear;
          EXPECT_NEAR(got, lit, 1e-3f * lit)
              << (k ? "far" : "near") << ": lit at " << p.x << "," << p.y;
        }
      }
    EXPECT_GT(umbra, 40);
    EXPECT_GT(clear, 2500);
  }
  EXPECT_EQ(f[0].attributes.at("nestlight:shadow_texel:0"),
            f[1].attributes.at("nestlight:shadow_texel:0"));
  // Both frames fit the same map, so the shadow is the same; what differs is the camera's far
  // plane (1000 km with the far box) and with it the depth the G-buffer reconstructs positions
  // from (about 1e-7 m here), which could flip a pixel exactly on a PCF edge: at most 1% of the
  // floor's pixels may change side, where the bounds-wide map lost every umbra pixel.
  int floorPixels = 0, changed = 0;
  for (size_t i = 0; i < dark[0].size(); ++i) {
    if (dark[0][i] < 0) continue;
    ++floorPixels;
    changed += dark[0][i] != dark[1][i];
  }
  std::printf("sun: shadow texel %s m; %d of %d floor pixels changed side with the far box\n",
              f[0].attributes.at("nestlight:shadow_texel:0").c_str(), changed, floorPixels);
  EXPECT_LE(changed, floorPixels / 100) << "pixels whose shadow changed with the far box";
}

// The fit on the CPU: the texel grid stays put in the world while the camera moves (the map's
// origin moves in whole texels, its size in quarter octaves), a far box out of view changes
// nothing, and a camera that sees nothing gets the whole scene.
TEST(Raster, DirectionalShadowFitKeepsItsTexelGrid) {
  const std::vector<ShadowBox> near = {{{-10, -10, -0.1f}, {10, 10, 0}},
                                       {{-0.5f, -0.5f, 1}, {0.5f, 0.5f, 1.2f}}};
  std::vector<ShadowBox> far = near;
  far.push_back({{1e6f, 0, 0}, {1e6f + 20, 20, 20}});
  const glm::vec3 dir(-0.4f, -0.3f, -0.87f);
  const DirectionalShadowFit whole = fitDirectionalShadow(dir, near, nullptr, 512);
  EXPECT_FALSE(whole.fitted);
  float texel = 0;
  double phase = -1;
  for (int i = 0; i < 40; ++i) {
    ShadowFitCamera cam;
    const glm::vec3 eye(0.037f * float(i), 0.011f * float(i), 6.0f);
    cam.viewFromWorld = glm::lookAt(eye, eye - glm::vec3(0, 0.001f, 6), glm::vec3(0, 1, 0));
    cam.tanHalfFovY = std::tan(glm::radians(30.0f));
    cam.nearZ = 4, cam.farZ = 20;
    const DirectionalShadowFit a = fitDirectionalShadow(dir, near, &cam, 512);
    cam.farZ = 1.1e6f;  // the far box moves the far plane too
    const DirectionalShadowFit b = fitDirectionalShadow(dir, far, &cam, 512);
    ASSERT_TRUE(a.fitted);
    EXPECT_EQ(a.clipFromWorld, b.clipFromWorld) << i;
    EXPECT_LT(a.texel, 0.5f * whole.texel) << "the view's part of the floor, not all of it";
    if (i == 0) texel = a.texel;
    EXPECT_EQ(a.texel, texel) << i;
    // A fixed world point sits at the same place within its texel in every fit.
    const glm::vec4 c = a.clipFromWorld * glm::vec4(0.3f, -0.2f, 0.0f, 1.0f);
    const double u = (double(c.x) + 1) * 256, frac = u - std::floor(u);
    if (phase < 0) phase = frac;
    EXPECT_NEAR(std::min(std::abs(frac - phase), 1 - std::abs(frac - phase)), 0.0, 2e-3) << i;
  }
  ShadowFitCamera away;
  away.viewFromWorld = glm::lookAt(glm::vec3(0, 0, 100), glm::vec3(0, 0, 200), glm::vec3(0, 1, 0));
  EXPECT_FALSE(fitDirectionalShadow(dir, near, &away, 512).fitted);
}

}  // namespace
}  // namespace nestlight::gi
