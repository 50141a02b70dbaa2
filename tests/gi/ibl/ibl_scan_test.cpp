// The `ibl` method on a scanned receiver: a floor of scan points (uniformly random and
// Poisson-disk, with the scan's noise along the normal) in the albedo mode, where every point is a
// Lambert reflector of its colour, under a constant sky and under a single-texel sun. The closed
// forms are those of the meshes' floor (ibl_test.cpp); the scan must neither shadow itself (its own
// discs and clusters stop a receiver's rays: dark speckle and bands) nor leave fireflies.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>

#include "gi/floor_scene.h"
#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/mesh.h"
#include "nestlight/gi/method.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/sampling.h"
#include "nestlight/gi/scene.h"
#include "nestlight/gi/srgb.h"
#include "test_support.h"

namespace nestlight::gi {
namespace {

using json = nlohmann::json;
constexpr int kGrey = 188;      // the scan's colour (8-bit sRGB)
constexpr double kSide = 12.0;  // the floor: kSide x kSide m about the origin

// A 12 x 12 m floor of 30,000 scan points (7 cm apart), uniformly random or Poisson-disk (weighted
// sample elimination, gi::sampleSurfels), each moved along its normal by Gaussian noise of
// `noise` metres (a terrestrial scanner's range noise: the generated scenes use 1 to 3 mm); the
// normals are the surface's, as the generated scenes' are.
void buildScannedFloor(const test::TempDir& t, bool poisson, double noise) {
  TriangleMesh quad;
  const float h = float(kSide / 2);
  quad.positions = {{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}};
  quad.indices = {0, 1, 2, 0, 2, 3};
  SurfelOptions so;
  so.method = poisson ? SurfelSampling::PoissonDisk : SurfelSampling::AreaUniform;
  so.count = 30000;
  so.seed = poisson ? 3 : 4;
  const Surfels s = sampleSurfels(quad, glm::mat4(1.0f), so);
  Rng rng(poisson ? 11 : 12);
  auto gauss = [&] {
    const glm::vec2 g = rng.uniform2();
    return std::sqrt(-2 * std::log(std::max(g.x, 1e-12f))) * std::cos(2 * kPi * g.y);
  };
  std::ofstream ply(t.file("floor.ply"));
  ply << "ply\nformat ascii 1.0\nelement vertex " << s.positions.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty "
         "float ny\n"
         "property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar "
         "blue\nend_header\n";
  for (const glm::vec3& p : s.positions)
    ply << p.x << " " << p.y << " " << noise * gauss() << " 0 0 1 " << kGrey << " " << kGrey << " "
        << kGrey << "\n";
  ply.close();
  test::buildOctreeFrom(t.file("floor.ply"), t.path() / "floor.octree");
}

Scene scannedFloorScene(const test::TempDir& t, const json& environment, const json& parameters,
                        int size) {
  json j = {
      {"version", 1},
      {"origin", {0.0, 0.0, 0.0}},  // world = local, as floorPoint() assumes
      {"octrees", {{{"path", "floor.octree"}}}},
      {"environment", environment},
      {"camera",
       {{"eye", {0.0, -4.0, 1.6}},
        {"target", {0.0, 0.0, 0.0}},
        {"up", {0.0, 0.0, 1.0}},
        {"fov", 30.0},
        {"width", size},
        {"height", size}}},
      {"gi", {{"method", "ibl"}, {"mode", "albedo"}, {"seed", 5}, {"parameters", parameters}}}};
  std::ofstream(t.file("scene.json")) << j.dump(2);
  return loadScene(t.file("scene.json"));
}

// A 64 x 32 map of black but for texel (20, 11) of radiance E: 61.9 to 67.5 degrees from the
// zenith (a low sun: rays 22 to 28 degrees above the floor, where a scan's noise shadows most).
// The floor sees it whole: L_o = rho / pi * E * (2 pi / 64) * (cos^2 theta0 - cos^2 theta1) / 2.
struct LowSun {
  HdrImage map{64, 32};
  double irradianceOverPi = 0;
  explicit LowSun(float E) {
    map.set(20, 11, Rgb(E));
    const double th0 = std::numbers::pi * 11 / 32, th1 = std::numbers::pi * 12 / 32;
    irradianceOverPi = E / std::numbers::pi * (2 * std::numbers::pi / 64) *
                       (std::pow(std::cos(th0), 2) - std::pow(std::cos(th1), 2)) / 2;
  }
};

struct Ratios {
  double mean = 0, lowest = 1e30, highest = 0;
  int n = 0, below = 0;
};

// Every floor pixel's ratio of rendered to closed-form radiance (red channel).
Ratios ratios(const Scene& s, const MethodFrame& f, double want, double floorAt,
              const std::vector<uint8_t>& mask) {
  Ratios r;
  for (int y = 0; y < s.camera.height; ++y)
    for (int x = 0; x < s.camera.width; ++x) {
      glm::vec3 p;
      if (!mask[size_t(y) * size_t(s.camera.width) + size_t(x)] ||
          !floorPoint(s, x, y, &p, float(kSide / 2 - 0.1)))
        continue;
      const double v = f.image.get(x, y).r / want;
      r.mean += v, r.n++;
      r.lowest = std::min(r.lowest, v), r.highest = std::max(r.highest, v);
      r.below += v < floorAt;
    }
  r.mean /= std::max(r.n, 1);
  return r;
}

// The pixels whose receiver the G-buffer holds whole: unshadowed (visibility off) in a furnace
// every receiver returns rho L exactly (BSDF sampling of a Lambert reflector under a uniform sky:
// every sample is rho L). The rest are the raster frame's holes between a random scan's splats (at
// a grazing view about 1% of the pixels, black without a receiver or with a splat's depth and no
// colour), the G-buffer's business and not this method's.
std::vector<uint8_t> receiverMask(Scene s, double rho) {
  s.environment = SceneEnvironment{};
  s.environment->constant = Rgb(1.0f);
  s.gi.parameters = {{"estimator", "brdf"}, {"brdf_samples", 1}, {"visibility", false}};
  const MethodFrame f = createMethod(s, {true, false})->render(s.camera);
  std::vector<uint8_t> m(size_t(s.camera.width) * size_t(s.camera.height));
  for (int y = 0; y < s.camera.height; ++y)
    for (int x = 0; x < s.camera.width; ++x)
      m[size_t(y) * size_t(s.camera.width) + size_t(x)] =
          std::abs(f.image.get(x, y).r / rho - 1) < 1e-3;
  return m;
}

// Every estimator on a scanned floor under both lights, the floor seen at 22 degrees (a street
// seen from a few metres up, as the object scene's camera sees its town).
//   Means within 2%: the Monte Carlo error of the mean of ~3,700 pixels is under 0.5% at these
//   counts; what is left is the scan shadowing itself, which only darkens (the issue measured
//   0.81 to 0.85 of the reference).
//   No pixel below 0.8: a receiver whose rays its own surface stops. The counts keep a pixel's own
//   noise to a standard deviation under 4% (MIS under the sky takes most samples from the BSDF:
//   environment samples of a uniform sky fall below the horizon half the time), so 0.8 is 5
//   of them off. Not where an estimator sees the light only by chance: environment sampling
//   alone under a uniform sky (a standard deviation of 0.46 a sample: the mean only) and BSDF
//   sampling alone under a single texel (found by 0.1% of its samples: left out, as not even
//   the mean of the image settles within 2% at a test's budget).
//   No pixel above 3 times the closed form: a firefly (the issue saw 6 times the reference's
//   brightest pixel on 0.5% of pixels from BIS and SMC); noise alone reaches 1.3 at most.
//   SMC renders two frames of a still camera: the second carries the first's samples.
void checkScannedFloor(bool poisson) {
  const float rho = srgbDecode(kGrey / 255.0f);
  const LowSun sun(400.0f);
  test::TempDir t;
  buildScannedFloor(t, poisson, 0.002);
  writeExr(t.file("sun.exr"), sun.map);
  const std::vector<uint8_t> mask =
      receiverMask(scannedFloorScene(t, {{"constant", 1.0}}, json::object(), 64), rho);
  for (bool sky : {true, false}) {
    const json env = sky ? json{{"constant", 1.0}} : json{{"path", "sun.exr"}};
    const double want = sky ? rho * 1.0 : rho * sun.irradianceOverPi;
    for (const char* e : {"mis", "bis", "smc", "env", "brdf"}) {
      const std::string est = e;
      if (!sky && est == "brdf") continue;
      json p = {{"estimator", est},     {"brdf_samples", 16}, {"env_samples", 16},
                {"bis_proposals", 128}, {"bis_samples", 8},   {"smc_particles", 8}};
      if (est == "mis" && sky) p["brdf_samples"] = 28, p["env_samples"] = 4;
      Scene s = scannedFloorScene(t, env, p, 64);
      auto m = createMethod(s, {true, false});
      MethodFrame f = m->render(s.camera);
      if (est == "smc") f = m->render(s.camera);
      const Ratios r = ratios(s, f, want, 0.8, mask);
      std::printf(
          "%s floor, %s, %-4s: mean %.4f, lowest %.3f, highest %.3f, %d of %d pixels below 0.8\n",
          poisson ? "Poisson" : "random", sky ? "sky" : "sun", e, r.mean, r.lowest, r.highest,
          r.below, r.n);
      const std::string what = std::string(sky ? "sky, " : "sun, ") + e;
      ASSERT_GT(r.n, 3000) << what;
      EXPECT_NEAR(r.mean, 1.0, 0.02) << what;
      if (!(sky && est == "env")) {
        EXPECT_EQ(r.below, 0) << what << ": lowest pixel " << r.lowest;
        EXPECT_LT(r.highest, 3.0) << what;
      }
    }
  }
}

// A scanned dome: a convex surface sees its whole hemisphere, so under a uniform sky every
// receiver returns rho L, on the curve as on the floor. A curved scan is where a hierarchy's
// pruned clusters (one disc in their points' mean plane) would stand above the points at their
// rims, by up to a fifth of their radius, and stop the rays of the receivers there (the object
// scene's scanned sphere carried dark rings; here 190 pixels below 0.8, mean 0.93, before rays met
// the points themselves). A sphere of 10 m, 30,000 points (20 cm apart, as coarse as the object
// scene's town), 2 mm of noise, seen from 41 m; pixels whose surface is seen more than 70 degrees
// off its normal are left out (the silhouette: a pixel there straddles sphere and background).
// Tolerances as on the floor.
TEST(IblScan, AScannedDomeDoesNotShadowItself) {
  const float rho = srgbDecode(kGrey / 255.0f);
  const double R = 10;
  test::TempDir t;
  {
    const int n = 30000;
    Rng rng(21);
    std::ofstream ply(t.file("ball.ply"));
    ply << "ply\nformat ascii 1.0\nelement vertex " << n
        << "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty "
           "float ny\n"
           "property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar "
           "blue\nend_header\n";
    const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
      const double z = 1 - 2 * (i + 0.5) / n, r = std::sqrt(1 - z * z), phi = golden * i;
      const glm::dvec3 q(r * std::cos(phi), r * std::sin(phi), z);
      const glm::vec2 g = rng.uniform2();
      const double h =
          R + 0.002 * std::sqrt(-2 * std::log(std::max(g.x, 1e-12f))) * std::cos(2 * kPi * g.y);
      ply << h * q.x << " " << h * q.y << " " << h * q.z << " " << q.x << " " << q.y << " " << q.z
          << " " << kGrey << " " << kGrey << " " << kGrey << "\n";
    }
  }
  test::buildOctreeFrom(t.file("ball.ply"), t.path() / "floor.octree");
  auto scene = [&](const json& p) {
    json j = {{"version", 1},
              {"origin", {0.0, 0.0, 0.0}},
              {"octrees", {{{"path", "floor.octree"}}}},
              {"environment", {{"constant", 1.0}}},
              {"camera",
               {{"eye", {0.0, -4.0 * R, 1.0 * R}},
                {"target", {0.0, 0.0, 0.0}},
                {"up", {0.0, 0.0, 1.0}},
                {"fov", 32.0},
                {"width", 64},
                {"height", 64}}},
              {"gi", {{"method", "ibl"}, {"mode", "albedo"}, {"seed", 5}, {"parameters", p}}}};
    std::ofstream(t.file("ball.json")) << j.dump(2);
    return loadScene(t.file("ball.json"));
  };
  const std::vector<uint8_t> mask = receiverMask(scene(json::object()), rho);
  for (const char* e : {"mis", "bis", "smc", "env", "brdf"}) {
    const std::string est = e;
    json p = {{"estimator", est},
              {"brdf_samples", est == "mis" ? 28 : 16},
              {"env_samples", est == "mis" ? 4 : 16},
              {"bis_proposals", 128},
              {"bis_samples", 8},
              {"smc_particles", 8}};
    Scene s = scene(p);
    const MethodFrame f = createMethod(s, {true, false})->render(s.camera);
    Ratios r;
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) {
        glm::vec3 o, d;
        cameraRay(s.camera, s.origin, x + 0.5f, y + 0.5f, &o, &d);
        const float b = glm::dot(o, d), c = glm::dot(o, o) - float(R * R);
        if (b * b - c <= 0 || !mask[size_t(y) * 64 + size_t(x)]) continue;
        const glm::vec3 q = o + d * (-b - std::sqrt(b * b - c));
        if (-glm::dot(q, d) < 0.34f * float(R)) continue;  // cos 70 degrees
        const double v = f.image.get(x, y).r / rho;
        r.mean += v, r.n++, r.lowest = std::min(r.lowest, v), r.highest = std::max(r.highest, v),
                            r.below += v < 0.8;
      }
    r.mean /= std::max(r.n, 1);
    std::printf(
        "dome, sky, %-4s: mean %.4f, lowest %.3f, highest %.3f, %d of %d pixels below 0.8\n", e,
        r.mean, r.lowest, r.highest, r.below, r.n);
    ASSERT_GT(r.n, 1500) << e;
    EXPECT_NEAR(r.mean, 1.0, 0.02) << e;
    if (est != "env") {
      EXPECT_EQ(r.below, 0) << e << ": lowest pixel " << r.lowest;
    }
  }
}

TEST(IblScan, ARandomFloorNeitherShadowsItselfNorSparkles) {
  checkScannedFloor(false);
}
TEST(IblScan, APoissonFloorNeitherShadowsItselfNorSparkles) {
  checkScannedFloor(true);
}

}  // namespace
}  // namespace nestlight::gi
