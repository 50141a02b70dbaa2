// The `diffrender` method against closed forms: a black sphere of radius r whose centre is D above
// a scanned floor (radiance-cache mode: the scan's colour is its captured radiance) under a
// constant sky L. A floor point at distance d from the centre sees the sphere, wholly above its
// horizon, with the cosine-weighted solid angle pi (r/d)^2 cos(theta) = pi r^2 D / d^3; the black
// sphere takes that share of the sky, so dL = -rho L r^2 D / d^3 (-rho L (r/D)^2 at its foot).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>

#include "gi/floor_scene.h"
#include "nestlight/converters/test_scenes.h"
#include "nestlight/gi/diffrender/diffrender_method.h"
#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/method.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/scene.h"
#include "nestlight/gi/srgb.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/node_key.h"
#include "test_support.h"

namespace nestlight::gi {
namespace {

using json = nlohmann::json;
constexpr int kGrey = 160;    // the floor's recorded colour (8-bit sRGB)
constexpr float kSky = 2.0f;  // the sky's radiance
constexpr float kR = 0.5f, kD = 1.5f;

// An 8 x 8 m grid of scan points 4 cm apart at z = 0, normals up.
void buildFloor(const test::TempDir& t) {
  std::vector<ScanPoint> points;
  const int n = 201;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      points.push_back({{-4.0 + 0.04 * i, -4.0 + 0.04 * j, 0}, {0, 0, 1}, kGrey, kGrey, kGrey});
  writeScanPly(t.file("floor.ply"), points);
  test::buildOctreeFrom(t.file("floor.ply"), t.path() / "floor.octree");
  writeIcosphereObj(t.file("sphere.obj"), 4);
}

// The floor's captured radiance is rho L: colour_scale L with rho the recorded colour.
json sceneJson(const json& parameters, const std::string& method, int size, float sky = kSky) {
  return {
      {"version", 1},
      {"origin", {0.0, 0.0, 0.0}},
      {"octrees", {{{"path", "floor.octree"}, {"colour_scale", sky}}}},
      {"materials", {{"black", {{"type", "lambert"}, {"base_color", 0.0}}}}},
      {"meshes",
       {{{"path", "sphere.obj"},
         {"transform", {{"scale", kR}, {"translate", {0.0, 0.0, kD}}}},
         {"material", "black"}}}},
      {"environment", {{"constant", {sky, sky, sky}}}},
      {"camera",
       {{"eye", {0.0, -3.2, 2.4}},
        {"target", {0.0, 0.4, 0.0}},
        {"up", {0.0, 0.0, 1.0}},
        {"fov", 50.0},
        {"width", size},
        {"height", size}}},
      {"gi",
       {{"method", method}, {"mode", "radiance_cache"}, {"seed", 3}, {"parameters", parameters}}}};
}

Scene writeScene(const test::TempDir& t, const json& j) {
  std::ofstream(t.file("scene.json")) << j.dump(2);
  return loadScene(t.file("scene.json"));
}

MethodFrame renderWith(const test::TempDir& t, const json& parameters, const std::string& method,
                       int size, float sky = kSky) {
  const Scene s = writeScene(t, sceneJson(parameters, method, size, sky));
  auto m = createMethod(s, MethodContext(true));
  return m->render(s.camera);
}

// The floor's change under the black sphere (with - without) against the closed form, summed over
// the floor pixels within 2 m of its foot where the camera sees the floor and its capture.
struct SphereShadow {
  double measured = 0, expected = 0;
  int pixels = 0;
};
SphereShadow sphereShadow(const Scene& s, const HdrImage& with, const HdrImage& without,
                          float sky) {
  const float rho = srgbDecode(kGrey / 255.0f);
  SphereShadow r;
  for (int y = 0; y < with.height; ++y)
    for (int x = 0; x < with.width; ++x) {
      glm::vec3 p;
      if (!floorPoint(s, x, y, &p, 3.5f)) continue;
      const float h = std::hypot(p.x, p.y);
      if (h > 2.0f) continue;
      const Rgb b = without.get(x, y);
      if (std::abs(b.r - rho * sky) > 0.02f * rho * sky) continue;
      const float d = std::sqrt(h * h + kD * kD);
      r.expected += -rho * sky * kR * kR * kD / (d * d * d);
      r.measured += with.get(x, y).r - b.r;
      ++r.pixels;
    }
  return r;
}

class DiffrenderSphere : public ::testing::TestWithParam<const char*> {};

TEST_P(DiffrenderSphere, BlackSphereTakesItsShareOfTheSkyFromTheFloor) {
  test::TempDir t;
  buildFloor(t);
  const int size = 96;
  const json params = {{"query", GetParam()}, {"samples", 64},    {"cache", 64},
                       {"object_voxels", 64}, {"delta_scale", 1}, {"aovs", "aovs"}};
  const MethodFrame with = renderWith(t, params, "diffrender", size);
  const MethodFrame without = renderWith(t, json::object(), "raster", size);
  const Scene s = writeScene(t, sceneJson(params, "diffrender", size));
  const float rho = srgbDecode(kGrey / 255.0f);
  const SphereShadow shadow = sphereShadow(s, with.image, without.image, kSky);
  ASSERT_GT(shadow.pixels, 1000);
  // The material estimate (eq. 5) on the floor: the capture over the impostor's mean sky, which the
  // sphere (not in the impostor) does not take: rho everywhere, within 3% on average (the
  // impostor's texels at the horizon mix floor and sky) and 10% at any pixel.
  const HdrImage rhoAov = readHdrImage((t.path() / "aovs" / "diffrender_rho.exr").string());
  const HdrImage mask = readHdrImage((t.path() / "aovs" / "diffrender_mask.exr").string());
  ASSERT_EQ(rhoAov.width, size);
  double rhoSum = 0;
  int rhoPixels = 0, objectPixels = 0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      objectPixels += mask.get(x, y).r == 2.0f;
      if (mask.get(x, y).r != 1.0f) continue;
      rhoSum += rhoAov.get(x, y).r, ++rhoPixels;
      EXPECT_NEAR(rhoAov.get(x, y).r / rho, 1.0, 0.1) << x << "," << y;
    }
  ASSERT_GT(rhoPixels, 1000);
  EXPECT_GT(objectPixels, 50);
  EXPECT_NEAR(rhoSum / rhoPixels / rho, 1.0, 0.03);
  // 5%: the bound; the estimator's noise over these pixels is under 1% (64 samples, all
  // traced), the 64^3 voxels' silhouette about 1%, the rest is the impostor's.
  EXPECT_NEAR(shadow.measured / shadow.expected, 1.0, 0.05)
      << GetParam() << ": " << shadow.pixels << " floor pixels, " << with.summary;
}

// Hard cases. A sky far beyond half float's range (1e6, the capture ~0.35e6): the impostor and
// dL are single floats, so the sphere takes its share as at radiance 2 (within 5%), nothing
// overflows. And a sphere under the floor: every scan direction leaves upwards, none meets its box
// (|H| = 0), so the composite is the capture bit for bit.
TEST(DiffrenderHardCases, SkyBeyondHalfFloatAndNoBoxHit) {
  test::TempDir t;
  buildFloor(t);
  const int size = 96;  // the black-sphere test's settings
  const float sky = 1e6f;
  const json params = {{"query", "dit"},      {"samples", 64},    {"cache", 64},
                       {"object_voxels", 64}, {"delta_scale", 1}, {"aovs", "aovs"}};
  const MethodFrame with = renderWith(t, params, "diffrender", size, sky);
  const MethodFrame without = renderWith(t, json::object(), "raster", size, sky);
  for (float v : with.image.rgb) ASSERT_TRUE(std::isfinite(v));
  const SphereShadow shadow = sphereShadow(
      writeScene(t, sceneJson(params, "diffrender", size, sky)), with.image, without.image, sky);
  ASSERT_GT(shadow.pixels, 400);
  EXPECT_NEAR(shadow.measured / shadow.expected, 1.0, 0.05) << with.summary;

  json below = sceneJson(params, "diffrender", size);
  below["meshes"][0]["transform"]["translate"] = {0.0, 0.0, -1.5};
  const Scene s = writeScene(t, below);
  const MethodFrame under = createMethod(s, MethodContext(true))->render(s.camera);
  below["gi"]["method"] = "raster";
  below["gi"]["parameters"] = json::object();
  const Scene r = writeScene(t, below);
  const MethodFrame capture = createMethod(r, MethodContext(true))->render(r.camera);
  EXPECT_EQ(under.attributes.at("nestlight:diffrender_box_hits"), "0");
  const HdrImage mask = readHdrImage((t.path() / "aovs" / "diffrender_mask.exr").string());
  int scan = 0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      if (mask.get(x, y).r != 1.0f) continue;
      ++scan;
      const Rgb a = under.image.get(x, y), b = capture.image.get(x, y);
      ASSERT_TRUE(a.r == b.r && a.g == b.g && a.b == b.b) << x << "," << y;
    }
  EXPECT_GT(scan, 2000);
}

INSTANTIATE_TEST_SUITE_P(Queries, DiffrenderSphere, ::testing::Values("dit", "em", "vct", "exact"));

// The scene's lights lit the capture but are no surface of it: a sun straight down (irradiance E,
// no sky) over the floor, whose captured radiance is then rho E / pi; the black sphere's umbra (the
// disc of radius r under it) loses all of it, dL = -rho E / pi, and the floor outside keeps its
// capture exactly (nothing else changes: the sphere is black and the impostor holds no light).
TEST(DiffrenderLights, InsertedMeshShadowsTheSunOnTheCapture) {
  test::TempDir t;
  buildFloor(t);
  const float E = 3.0f;
  const int size = 96;
  json j = sceneJson({{"samples", 16}, {"cache", 8}, {"object_voxels", 32}, {"delta_scale", 1}},
                     "diffrender", size);
  j.erase("environment");
  j["octrees"][0]["colour_scale"] = E / kPi;
  j["lights"] = json::array(
      {json{{"type", "directional"}, {"direction", {0.0, 0.0, -1.0}}, {"irradiance", {E, E, E}}}});
  const Scene s = writeScene(t, j);
  const MethodFrame with = createMethod(s, MethodContext(true))->render(s.camera);
  j["gi"]["method"] = "raster";
  j["gi"]["parameters"] = json::object();
  const Scene r = writeScene(t, j);
  const MethodFrame without = createMethod(r, MethodContext(true))->render(r.camera);
  const float capture = srgbDecode(kGrey / 255.0f) * E / kPi;
  int umbra = 0, lit = 0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      glm::vec3 p;
      if (!floorPoint(s, x, y, &p, 3.5f)) continue;
      const Rgb b = without.image.get(x, y);
      if (std::abs(b.r - capture) > 0.02f * capture) continue;  // the sphere, not the floor
      const float h = std::hypot(p.x, p.y), got = with.image.get(x, y).r;
      if (h < 0.8f * kR) {
        // The shadow maps' 3 x 3 filter softens the edge only.
        EXPECT_LT(got, 0.05f * capture) << x << "," << y << " h " << h;
        ++umbra;
      } else if (h > 1.4f * kR) {
        EXPECT_NEAR(got, capture, 0.01f * capture) << x << "," << y << " h " << h;
        ++lit;
      }
    }
  EXPECT_GT(umbra, 30);
  EXPECT_GT(lit, 1000);
}

// A capture layer (what bake-radiance writes) stands for the scan's colour whatever gi.mode says:
// the floor's radiance rho L as a layer, in the albedo mode, renders as the radiance-cache scene
// whose colour is that radiance. Without one, the albedo mode is an error naming the field, and a
// layer the octree lacks names gi.parameters.capture.
TEST(DiffrenderCapture, LayerOfCapturedRadianceInTheAlbedoMode) {
  test::TempDir t;
  buildFloor(t);
  const float radiance = srgbDecode(kGrey / 255.0f) * kSky;
  test::writeColourLayer(t.path() / "floor.octree", "captured", [&](const NodeKey&, size_t) {
    return std::array<float, 3>{radiance, radiance, radiance};
  });
  const json params = {{"samples", 16}, {"object_voxels", 32}};
  const int size = 48;
  const MethodFrame cached = renderWith(t, params, "diffrender", size);
  json j = sceneJson(params, "diffrender", size);
  j["gi"]["mode"] = "albedo";
  const Error missing = test::errorOf([&] { createMethod(writeScene(t, j), MethodContext(true)); });
  EXPECT_NE(std::string(missing.what()).find("scene.gi.mode"), std::string::npos) << missing.what();
  j["gi"]["parameters"]["capture"] = "nope";
  const Error nope = test::errorOf([&] { createMethod(writeScene(t, j), MethodContext(true)); });
  EXPECT_NE(std::string(nope.what()).find("scene.gi.parameters.capture"), std::string::npos)
      << nope.what();
  j["gi"]["parameters"]["capture"] = "captured";
  const Scene s = writeScene(t, j);
  const MethodFrame layered = createMethod(s, MethodContext(true))->render(s.camera);
  double diff = 0, sum = 0;
  for (size_t i = 0; i < cached.image.rgb.size(); ++i)
    diff += std::abs(cached.image.rgb[i] - layered.image.rgb[i]), sum += cached.image.rgb[i];
  // The layer's half floats against the 8-bit colour decoded: 1e-3 of the image.
  EXPECT_LT(diff / sum, 1e-3);
  EXPECT_GT(sum, 0.0);
}

// A closed room of scan points (a 4 m cube, 9,600 at random, all of one radiance c) about the
// sphere, under a sky ten times brighter: every direction from the floor meets a wall, so the
// material estimate is c / c = 1 wherever the impostor is closed. Gaps between the splats that
// showed the sky (the pull-push fill closes them) would pull it below 1.
// A closed 4 m room of scan points (grey, normals inward) about the black sphere, under a sky of
// 10 that no scan pixel should see: 40 x 40 random points a side, or with `grid` 100 x 100 on a
// grid (4 cm); with `meshCeiling` the ceiling is a captured mesh (a box, "inserted": false,
// emitting the sky's radiance) instead of points.
json closedRoomScene(const test::TempDir& t, bool grid, bool meshCeiling, const json& parameters) {
  std::vector<ScanPoint> points;
  const int perSide = grid ? 100 : 40;
  Rng rng(7);
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side)
      for (int k = 0; k < perSide * perSide; ++k) {
        glm::vec3 p(0.0f), nn(0.0f);
        p[axis] = side ? 4.0f : 0.0f;
        // Uniformly random: the gaps between splats that a regular grid would not leave.
        const glm::vec2 u = meshCeiling
                                ? (glm::vec2(k % perSide, k / perSide) + 0.5f) / float(perSide)
                                : rng.uniform2();
        p[(axis + 1) % 3] = 4.0f * u.x;
        p[(axis + 2) % 3] = 4.0f * u.y;
        nn[axis] = side ? -1.0f : 1.0f;
        if (!(meshCeiling && axis == 2 && side == 1))
          points.push_back({p - glm::vec3(2, 2, 0), nn, 128, 128, 128});
      }
  writeScanPly(t.file("room.ply"), points);
  test::buildOctreeFrom(t.file("room.ply"), t.path() / "floor.octree");
  writeIcosphereObj(t.file("sphere.obj"), 3);
  json j = sceneJson(parameters, "diffrender", 48);
  j["environment"] = {{"constant", {10.0, 10.0, 10.0}}};
  j["camera"] = {{"eye", {0.0, -1.8, 3.0}},
                 {"target", {0.0, 0.5, 0.0}},
                 {"up", {0.0, 0.0, 1.0}},
                 {"fov", 70.0},
                 {"width", 48},
                 {"height", 48}};
  if (meshCeiling) {
    writeBoxObj(t.path() / "box.obj");
    j["materials"]["panel"] = {
        {"type", "lambert"}, {"base_color", 0.0}, {"emission", {10.0, 10.0, 10.0}}};
    j["meshes"].push_back(
        {{"path", "box.obj"},
         {"transform", {{"translate", {-2.0, -2.0, 4.0}}, {"scale", {4.0, 4.0, 0.1}}}},
         {"material", "panel"},
         {"inserted", false}});
  }
  return j;
}

TEST(DiffrenderImpostor, ClosedRoomShowsNoSkyThroughItsSplats) {
  test::TempDir t;
  const json j = closedRoomScene(t, false, false,
                                 {{"samples", 32},
                                  {"object_voxels", 32},
                                  {"rho_max", 4.0},
                                  {"aovs", "aovs"},
                                  {"compare_exact", true}});
  const Scene s = writeScene(t, j);
  const MethodFrame f = createMethod(s, MethodContext(true))->render(s.camera);
  const HdrImage rhoAov = readHdrImage((t.path() / "aovs" / "diffrender_rho.exr").string());
  double sum = 0;
  int n = 0;
  for (float v : rhoAov.rgb)
    if (v > 0) sum += v, ++n;
  ASSERT_GT(n, 300);
  EXPECT_NEAR(sum / n, 1.0, 0.03);
  // A closed convex room is one layer seen from any centre inside: DIT's hits are the exact rays'
  // up to a texel's footprint (compare_exact), bar the rare ray whose search or secant misses it.
  const double compared = std::stod(f.attributes.at("nestlight:diffrender_compared"));
  ASSERT_GT(compared, 1000);
  EXPECT_GT(std::stod(f.attributes.at("nestlight:diffrender_within_footprint")) / compared, 0.98);
}

// vct's cones in the same closed room under a sky 23 times as bright as its walls: what leaks in
// shows in the material estimate, rho = W / ((1 - f) W + f S) for walls W, sky S and f the share
// of the cones that see the sky. The walls, one voxel thick, hold at every level because the
// opacity is read by direction (averaged mips let the sky through them), the mips are whole
// halvings (an odd size's mip drops the ceiling), the room's bounds have a voxel of margin (a
// wall on the edge was not voxelised), and a cone leaving the floor is read clear of the floor's
// own voxels without being blinded to the walls: f was 80% before all that; now 4% (16% with
// Crassin et al.'s squared weights, 7% with trilinear reads), from the 1.5 voxels above a surface
// that its own cones cannot tell from it and the wall voxels no point fell in. 4 cm random points
// in 8.5 cm voxels.
TEST(DiffrenderVct, ClosedRoomKeepsTheSkyOutOfItsCones) {
  test::TempDir t;
  const json j = closedRoomScene(t, true, false,
                                 {{"query", "vct"},
                                  {"samples", 32},
                                  {"scene_voxels", 48},
                                  {"rho_max", 4.0},
                                  {"aovs", "aovs"}});
  const Scene s = writeScene(t, j);
  const MethodFrame f = createMethod(s, MethodContext(true))->render(s.camera);
  const HdrImage rhoAov = readHdrImage((t.path() / "aovs" / "diffrender_rho.exr").string());
  const double walls = srgbDecode(128.0f / 255.0f) * kSky, sky = 10.0;
  double leak = 0;
  int n = 0;
  for (float v : rhoAov.rgb)
    if (v > 0) leak += (walls / v - walls) / (sky - walls), ++n;
  ASSERT_GT(n, 300);
  EXPECT_LT(leak / n, 0.05) << f.summary;
  EXPECT_GT(leak / n, -0.05) << f.summary;  // no darker than the walls: nothing over-counted
}

// An inserted white Lambert sphere is lit by what the impostor holds: at a point of normal n,
// rho_s times the cosine-weighted mean of the sky (L) and of the floor's captured radiance below
// (integrated here over the 8 m floor's true extent). Its own volume must not shadow a convex
// surface: with self-shadowing on, the voxels a grazing ray passes near the surface it leaves are
// skipped (within 5% of the unshadowed light on the upper half).
TEST(DiffrenderObject, WhiteSphereIsLitByTheSkyAndTheFloor) {
  test::TempDir t;
  buildFloor(t);
  const int size = 64;
  const float rhoS = 0.8f, floorL = srgbDecode(kGrey / 255.0f) * kSky;
  for (const bool selfShadow : {false, true}) {
    SCOPED_TRACE(selfShadow ? "self-shadow" : "no self-shadow");
    json j = sceneJson({{"object_samples", 64},
                        {"object_voxels", 64},
                        {"self_shadow", selfShadow},
                        {"aovs", "aovs"}},
                       "diffrender", size);
    j["materials"]["black"]["base_color"] = rhoS;
    j["camera"]["eye"] = {0.0, -3.0, 3.2};
    j["camera"]["target"] = {0.0, 0.0, kD};
    j["camera"]["fov"] = 30.0;
    const Scene s = writeScene(t, j);
    const MethodFrame f = createMethod(s, MethodContext(true))->render(s.camera);
    const HdrImage mask = readHdrImage((t.path() / "aovs" / "diffrender_mask.exr").string());
    double got = 0, want = 0;
    int pixels = 0;
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        if (mask.get(x, y).r != 2.0f) continue;
        glm::vec3 o, d;
        cameraRay(s.camera, s.origin, x + 0.5f, y + 0.5f, &o, &d);
        const glm::vec3 oc = o - glm::vec3(0, 0, kD);
        const float b = glm::dot(oc, d), c = glm::dot(oc, oc) - kR * kR, disc = b * b - c;
        if (disc < 0) continue;
        const glm::vec3 p = o + d * (-b - std::sqrt(disc)),
                        n = glm::normalize(p - glm::vec3(0, 0, kD));
        if (n.z < 0.0f) continue;
        // The cosine-weighted mean over the hemisphere about n: sky, or the floor where the
        // direction meets it within its 8 m square.
        const glm::vec3 t1 = glm::normalize(glm::cross(
                            std::abs(n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0), n)),
                        t2 = glm::cross(n, t1);
        double sum = 0;
        const int k = 48;
        for (int a = 0; a < k; ++a)
          for (int bb = 0; bb < k; ++bb) {
            const float r = std::sqrt((a + 0.5f) / k), phi = 2 * kPi * (bb + 0.5f) / k;
            const glm::vec3 w = r * std::cos(phi) * t1 + r * std::sin(phi) * t2 +
                                std::sqrt(std::max(0.0f, 1 - r * r)) * n;
            bool floorHit = false;
            if (w.z < 0) {
              const glm::vec3 q = p + w * (-p.z / w.z);
              floorHit = std::abs(q.x) < 4 && std::abs(q.y) < 4;
            }
            sum += floorHit ? floorL : kSky;
          }
        want += rhoS * sum / (k * k);
        got += f.image.get(x, y).r;
        ++pixels;
      }
    ASSERT_GT(pixels, 100);
    EXPECT_NEAR(got / want, 1.0, 0.05) << pixels << " pixels";
  }
}

// Fig. 8's check: a photograph of the view in other colours, a known 3x3 map M away from the
// capture's (a camera's white balance and primaries), composites back into its own colours: with
// C = M^-1 as colour-match would find it, the composite equals M times the capture's composite
// within 1%. The photograph is the capture itself (raster's image of the scan), so with the
// identity map the composite is the capture's.
TEST(DiffrenderBackground, PhotographInOtherColoursCompositesBackThroughTheMap) {
  test::TempDir t;
  buildFloor(t);
  const int size = 48;
  const json params = {{"samples", 16}, {"object_voxels", 32}};
  json rasterScene = sceneJson(json::object(), "raster", size);
  const Scene rs = writeScene(t, rasterScene);
  const HdrImage capture = createMethod(rs, MethodContext(true))->render(rs.camera).image;
  writeExr(t.file("photo.exr"), capture);
  const glm::mat3 M(glm::vec3(0.9f, 0.05f, 0.0f), glm::vec3(0.1f, 0.8f, 0.2f),
                    glm::vec3(0.0f, 0.1f, 1.1f));  // columns
  HdrImage altered = capture;
  for (size_t i = 0; i < altered.rgb.size(); i += 3) {
    const glm::vec3 v = M * glm::vec3(capture.rgb[i], capture.rgb[i + 1], capture.rgb[i + 2]);
    altered.rgb[i] = v.x, altered.rgb[i + 1] = v.y, altered.rgb[i + 2] = v.z;
  }
  writeExr(t.file("photo_m.exr"), altered);
  const MethodFrame plain = renderWith(t, params, "diffrender", size);
  json p1 = params;
  p1["background"] = "photo.exr";
  const MethodFrame same = renderWith(t, p1, "diffrender", size);
  const glm::mat3 C = glm::inverse(M);
  json p2 = params;
  p2["background"] = "photo_m.exr";
  p2["background_map"] = json::array();
  for (int r = 0; r < 3; ++r) p2["background_map"].push_back({C[0][r], C[1][r], C[2][r]});
  const MethodFrame back = renderWith(t, p2, "diffrender", size);
  double d1 = 0, d2 = 0, sum = 0;
  for (size_t i = 0; i < plain.image.rgb.size(); i += 3) {
    const glm::vec3 a(plain.image.rgb[i], plain.image.rgb[i + 1], plain.image.rgb[i + 2]);
    const glm::vec3 b(same.image.rgb[i], same.image.rgb[i + 1], same.image.rgb[i + 2]);
    const glm::vec3 c(back.image.rgb[i], back.image.rgb[i + 1], back.image.rgb[i + 2]);
    d1 += glm::length(a - b), d2 += glm::length(M * a - c), sum += glm::length(M * a);
  }
  EXPECT_LT(d1 / sum, 1e-3);
  EXPECT_LT(d2 / sum, 0.01);
  // A photograph of another size is an error naming the field.
  HdrImage small(8, 8);
  writeExr(t.file("small.exr"), small);
  json p3 = params;
  p3["background"] = "small.exr";
  const Error e = test::errorOf([&] { renderWith(t, p3, "diffrender", size); });
  EXPECT_NE(std::string(e.what()).find("scene.gi.parameters.background"), std::string::npos)
      << e.what();
}

// Eq. 9 traces `cache` of a pixel's |H| box hits and scales their sum by |H| / cache: unbiased,
// so its mean over many independent pixels (each its own random sequence) equals the uncached
// estimator's (every hit traced) within 3 standard errors of the mean difference.
TEST(DiffrenderCache, ScaledSumOfTracedHitsIsUnbiased) {
  test::TempDir t;
  buildFloor(t);
  const int size = 64;
  const json common = {{"query", "em"}, {"samples", 32}, {"object_voxels", 32}, {"delta_scale", 1}};
  json cached = common, uncached = common;
  cached["cache"] = 1;
  uncached["cache"] = 32;
  const MethodFrame a = renderWith(t, cached, "diffrender", size);
  const MethodFrame b = renderWith(t, uncached, "diffrender", size);
  const Scene s = writeScene(t, sceneJson(common, "diffrender", size));
  EXPECT_LT(std::stod(a.attributes.at("nestlight:diffrender_traced")),
            0.5 * std::stod(a.attributes.at("nestlight:diffrender_box_hits")));
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      glm::vec3 p;
      if (!floorPoint(s, x, y, &p, 3.5f) || std::hypot(p.x, p.y) > 1.5f) continue;
      if (a.image.get(x, y).r == b.image.get(x, y).r) continue;  // no box hit: both exact
      const double d = a.image.get(x, y).r - b.image.get(x, y).r;
      sum += d, sum2 += d * d, ++n;
    }
  ASSERT_GT(n, 300);
  const double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / (n - 1));
  EXPECT_LT(std::abs(mean), 3 * se) << n << " pixels, mean difference " << mean << ", SE " << se;
  EXPECT_GT(se, 0.0);
}

// The exact query traces the captured scene's meshes like its scan: in a closed room (4 cm grid)
// whose ceiling is a captured mesh, exact rays meet something as often as when the ceiling is
// scanned (without the meshes, those to the ceiling, about half, would leave to the sky), and
// DIT, whose impostor holds the ceiling's emission and distance, agrees with them as with points.
// Every ray meets the closed room: the discs are the reference's, which cover their surface (with
// the level's spacing as radius 17% of the rays passed between them with the meshed ceiling, 28%
// with the scanned one).
TEST(DiffrenderExact, CapturedMeshesAreTracedLikeTheScan) {
  std::map<bool, double> met, within;
  for (bool mesh : {false, true}) {
    test::TempDir t;
    const Scene s =
        writeScene(t, closedRoomScene(t, true, mesh, {{"samples", 32}, {"compare_exact", true}}));
    const MethodFrame f = createMethod(s, MethodContext(true))->render(s.camera);
    const double rays = 32.0 * std::stod(f.attributes.at("nestlight:diffrender_scan_pixels"));
    const double compared = std::stod(f.attributes.at("nestlight:diffrender_compared"));
    ASSERT_GT(rays, 10000);
    met[mesh] = compared / rays;
    within[mesh] = std::stod(f.attributes.at("nestlight:diffrender_within_footprint")) / compared;
    std::printf("%s ceiling: %.4f of the rays met the scan, %.4f within a texel's footprint\n",
                mesh ? "meshed" : "scanned", met[mesh], within[mesh]);
  }
  EXPECT_GT(met[false], 0.999);
  EXPECT_GT(met[true], 0.999);
  EXPECT_GT(within[true], within[false] - 0.02) << within[false] << " with a scanned ceiling";
}

// DIT against exact rays in the protocol room (make-scene diffrender: the cornell room's walls and
// two blocks about the inserted object, 200k points): compare_exact traces every material ray both
// ways and counts the query's hits within an impostor texel's footprint of the exact hit. The
// impostor holds one layer, what its centre sees: a ray whose hit lies behind a block as seen from
// there stops at the block's silhouette. Over the hits the impostor holds DIT is within a texel's
// footprint for 0.971 (bound 0.9, the issue's); over all, 0.845 (bound 0.8: five in six strays
// end on hidden surfaces). EM, which does not march, is off on nearly all.
TEST(DiffrenderImpostor, DitHitsLieWithinATexelOfExactHitsInTheProtocolRoom) {
  test::TempDir t;
  TestSceneOptions o;
  o.points = 200'000;
  o.width = 48, o.height = 36;
  o.quiet = true;
  o.sharedData = t.path() / "no-data";  // the generated sphere, not the bunny
  const std::filesystem::path file = makeTestScene(TestSceneKind::Diffrender, t.path() / "room", o);
  json j = json::parse(test::readFile(file.string()));
  // The geometry is what is compared: the scan's colour as its radiance, no baked capture.
  j["gi"]["mode"] = "radiance_cache";
  std::map<std::string, double> within, withinSeen;
  for (const char* q : {"dit", "em"}) {
    j["gi"]["parameters"] = {{"query", q}, {"samples", 16}, {"compare_exact", true}};
    std::ofstream(file) << j.dump(2);
    const Scene s = loadScene(file);
    const MethodFrame f = createMethod(s, MethodContext(true))->render(s.camera);
    const double compared = std::stod(f.attributes.at("nestlight:diffrender_compared"));
    ASSERT_GT(compared, 1000) << q;
    within[q] = std::stod(f.attributes.at("nestlight:diffrender_within_footprint")) / compared;
    const double seen = std::stod(f.attributes.at("nestlight:diffrender_compared_seen"));
    ASSERT_GT(seen, 0.5 * compared) << q;
    withinSeen[q] = std::stod(f.attributes.at("nestlight:diffrender_within_footprint_seen")) / seen;
    std::printf(
        "%s: %.3f of %.0f hits within a texel's footprint of the exact hit, %.3f of the %.0f "
        "the impostor holds\n",
        q, within[q], compared, withinSeen[q], seen);
  }
  EXPECT_GE(within["dit"], 0.8);
  EXPECT_GE(withinSeen["dit"], 0.9);
  EXPECT_LT(within["em"], 0.1);
}

TEST(DiffrenderParameters, ErrorsNameTheField) {
  test::TempDir t;
  buildFloor(t);
  auto fails = [&](const json& params, const std::string& field) {
    const Scene s = writeScene(t, sceneJson(params, "diffrender", 32));
    try {
      diffrenderParameters(s);
      ADD_FAILURE() << params.dump() << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  fails({{"query", "rays"}}, "scene.gi.parameters.query");
  fails({{"samples", 8}, {"cache", 16}}, "scene.gi.parameters.cache");
  // The high preset's cache (32) shrinks to fewer samples given.
  EXPECT_EQ(diffrenderParameters(
                writeScene(t, sceneJson({{"quality", "high"}, {"samples", 16}}, "diffrender", 32)))
                .cache,
            16);
  fails({{"object_voxels", {1024, 1024, 1024}}}, "scene.gi.parameters.object_voxels");
  fails({{"object_voxels", {8, 8}}}, "scene.gi.parameters.object_voxels");
  fails({{"background", "no_such_photo.exr"}}, "scene.gi.parameters.background");
  fails({{"background_map", {{1, 0, 0}, {0, 1, 0}}}}, "scene.gi.parameters.background_map");
  fails({{"impostor_centre", {1.0, 2.0}}}, "scene.gi.parameters.impostor_centre");
  fails({{"impostor_centre", "middle"}}, "scene.gi.parameters.impostor_centre");
  EXPECT_EQ(*diffrenderParameters(writeScene(t, sceneJson({{"impostor_centre", {1.0, -2.0, 0.5}}},
                                                          "diffrender", 32)))
                 .impostorCentre,
            glm::dvec3(1.0, -2.0, 0.5));
  EXPECT_FALSE(diffrenderParameters(writeScene(t, sceneJson(json::object(), "diffrender", 32)))
                   .impostorCentre);
  fails({{"background_map", {{1, 0, 0}, {0, 1, 0}, {0, 2, 0}}}},
        "scene.gi.parameters.background_map");  // singular
  // Presets fill what is not given; given values win.
  const Scene high =
      writeScene(t, sceneJson({{"quality", "high"}, {"samples", 48}}, "diffrender", 32));
  const DiffrenderParameters p = diffrenderParameters(high);
  EXPECT_EQ(p.samples, 48);
  EXPECT_EQ(p.cache, 32);
  EXPECT_EQ(p.objectSamples, 128);
  EXPECT_EQ(p.objectVoxels, glm::ivec3(128, 96, 96));
  EXPECT_TRUE(p.secondaryBounce);
  const DiffrenderParameters low =
      diffrenderParameters(writeScene(t, sceneJson({{"quality", "low"}}, "diffrender", 32)));
  EXPECT_FALSE(low.selfShadow);
  EXPECT_EQ(low.objectVoxels, glm::ivec3(32));
}

TEST(DiffrenderMethod, NoInsertedMeshIsAnError) {
  test::TempDir t;
  buildFloor(t);
  json j = sceneJson(json::object(), "diffrender", 32);
  j["meshes"][0]["inserted"] = false;
  const Scene s = writeScene(t, j);
  try {
    auto m = createMethod(s, MethodContext(true));
    m->render(s.camera);
    ADD_FAILURE() << "a scene without inserted meshes rendered";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("scene.meshes"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace nestlight::gi
