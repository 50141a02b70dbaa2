// The `ibl` method (GL): every estimator unbiased in a furnace (exact) and under a single-texel
// sun (closed form), shadows by visibility rays, and SMC's normalising constant tracking a
// rotating map with the reinitialisation firing on a jump only.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>

#include "gi/floor_scene.h"
#include "gi/sphere_scan.h"
#include "nestlight/converters/test_scenes.h"
#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/material.h"
#include "nestlight/gi/method.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/reference/path_tracer.h"
#include "nestlight/gi/scene.h"
#include "test_support.h"

namespace nestlight::gi {
namespace {

using json = nlohmann::json;

// The floor (floor_scene.h), optionally a 2 x 2 m slab 1 m above it, and the environment.
Scene floorScene(const test::TempDir& t, const json& material, const json& environment,
                 const json& parameters, int size = 32, bool occluder = false) {
  json j = floorSceneJson(t, size);
  if (occluder)
    j["meshes"].push_back(
        json{{"path", "box.obj"},
             {"transform", {{"translate", {-1.0, -1.0, 1.0}}, {"scale", {2.0, 2.0, 0.1}}}},
             {"material", "floor"}});
  j["materials"] = {{"floor", material}};
  j["environment"] = environment;
  j["gi"] = {{"method", "ibl"}, {"mode", "albedo"}, {"seed", 7}, {"parameters", parameters}};
  std::ofstream(t.path() / "scene.json") << j.dump(2);
  return loadScene(t.path() / "scene.json");
}

struct Stats {
  double mean = 0, sd = 0;
  int n = 0;
};

// The floor pixels' ratio of rendered to expected radiance (red channel).
template <typename Want>
Stats ratioStats(const Scene& s, const MethodFrame& f, Want want) {
  Stats st;
  double sum = 0, sum2 = 0;
  for (int y = 0; y < s.camera.height; ++y)
    for (int x = 0; x < s.camera.width; ++x) {
      glm::vec3 p;
      if (!floorPoint(s, x, y, &p)) continue;
      const double r = f.image.get(x, y).r / want(p);
      sum += r, sum2 += r * r, st.n++;
    }
  st.mean = sum / st.n;
  st.sd = std::sqrt(std::max(0.0, sum2 / st.n - st.mean * st.mean));
  return st;
}

const char* kEstimators[] = {"mis", "bis", "smc", "env", "brdf"};

json estimatorParameters(const std::string& e) {
  return {{"estimator", e},      {"brdf_samples", 8}, {"env_samples", 8},
          {"bis_proposals", 64}, {"bis_samples", 8},  {"smc_particles", 8}};
}

// The furnace: a constant sky L over a convex floor. Lambert: every pixel returns rho L exactly;
// GGX: L times the material's directional albedo at the pixel's view (gi/core, by quadrature).
// Unbiased means the mean over the floor's ~900 pixels lies within 4 standard errors of the
// truth (the pixels are independent estimates), plus 0.2% for the float sums.
TEST(Ibl, EveryEstimatorIsUnbiasedInAFurnace) {
  for (bool glossy : {false, true}) {
    Material m;
    m.type = glossy ? MaterialType::GGX : MaterialType::Lambert;
    m.baseColor = Rgb(glossy ? 0.9f : 0.5f);
    m.roughness = 0.3f, m.metallic = 1;
    std::vector<double> want;  // per pixel, filled by the first estimator's pass
    for (const char* e : kEstimators) {
      test::TempDir t;
      const json material =
          glossy ? json{{"type", "ggx"}, {"base_color", 0.9}, {"roughness", 0.3}, {"metallic", 1.0}}
                 : json{{"type", "lambert"}, {"base_color", 0.5}};
      Scene s = floorScene(t, material, {{"constant", 2.0}}, estimatorParameters(e));
      const MethodFrame f = createMethod(s, {true, false})->render(s.camera);
      const glm::vec3 eye = glm::vec3(s.camera.eye - s.origin);
      size_t k = 0;
      const bool fill = want.empty();
      const Stats st = ratioStats(s, f, [&](const glm::vec3& p) {
        if (fill) {
          const glm::vec3 wo =
              glm::normalize(eye - p);  // the floor's frame is the world's (n = +z)
          want.push_back(glossy ? 2.0 * double(directionalAlbedo(m, wo, 20000, 3).r) : 1.0);
        }
        return want.at(k++);
      });
      ASSERT_GT(st.n, 500) << e;
      EXPECT_NEAR(st.mean, 1.0, 4 * st.sd / std::sqrt(double(st.n)) + 2e-3)
          << e << (glossy ? " ggx" : " lambert") << ": sd " << st.sd;
    }
  }
}

// A single-texel sun: a 16 x 8 map of radiance `sky`, but for texel (column, 2) of radiance E. A
// Lambert floor (rho 0.5) sees the texel whole above its horizon: L_o = rho / pi * E * integral
// over the texel of cos theta = rho / pi * E * (2 pi / 16) * (cos^2 theta0 - cos^2 theta1) / 2 at
// every floor point, plus rho times the sky (a uniform hemisphere).
struct SunTexel {
  HdrImage map{16, 8};
  double radiance = 0;  // what the floor returns
  SunTexel(float E, int column = 5, float sky = 0) {
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 16; ++x) map.set(x, y, Rgb(sky));
    map.set(column, 2, Rgb(E));
    const double th0 = std::numbers::pi * 2 / 8, th1 = std::numbers::pi * 3 / 8;
    radiance = 0.5 / std::numbers::pi * (E - sky) * (2 * std::numbers::pi / 16) *
                   (std::pow(std::cos(th0), 2) - std::pow(std::cos(th1), 2)) / 2 +
               0.5 * sky;
  }
};

TEST(Ibl, EveryEstimatorIsUnbiasedUnderASingleTexelSun) {
  test::TempDir t;
  const SunTexel sun(50.0f);
  writeExr(t.file("sun.exr"), sun.map);
  const double want = sun.radiance;
  for (const char* e : kEstimators) {
    json p = estimatorParameters(e);
    if (std::string(e) == "bis" || std::string(e) == "smc") p["bis_proposals"] = 256;
    Scene s = floorScene(t, {{"type", "lambert"}, {"base_color", 0.5}}, {{"path", "sun.exr"}}, p);
    const MethodFrame f = createMethod(s, {true, false})->render(s.camera);
    const Stats st = ratioStats(s, f, [&](const glm::vec3&) { return want; });
    ASSERT_GT(st.n, 500) << e;
    EXPECT_NEAR(st.mean, 1.0, 4 * st.sd / std::sqrt(double(st.n)) + 2e-3) << e << ": sd " << st.sd;
  }
}

// Sample counts beyond one dispatch's share (64 samples, 4,096 BIS proposals a pixel, kept below
// llvmpipe's loop limit) run as several passes whose sum is the same estimator: still unbiased
// under the sun texel, with the noise of all the samples (about sqrt(320 / 16) = 4.5 times less
// than 16 samples'), and no pixel near the loop limit.
TEST(Ibl, ManySamplesRunAsPasses) {
  test::TempDir t;
  const SunTexel sun(50.0f);
  writeExr(t.file("sun.exr"), sun.map);
  const double want = sun.radiance;
  double sd16 = 0;
  for (const json& p : {json{{"estimator", "mis"}, {"brdf_samples", 8}, {"env_samples", 8}},
                        json{{"estimator", "mis"}, {"brdf_samples", 160}, {"env_samples", 160}},
                        json{{"estimator", "bis"}, {"bis_proposals", 8192}, {"bis_samples", 16}}}) {
    Scene s =
        floorScene(t, {{"type", "lambert"}, {"base_color", 0.5}}, {{"path", "sun.exr"}}, p, 24);
    const MethodFrame f = createMethod(s, {true, false})->render(s.camera);
    const Stats st = ratioStats(s, f, [&](const glm::vec3&) { return want; });
    EXPECT_NEAR(st.mean, 1.0, 4 * st.sd / std::sqrt(double(st.n)) + 2e-3)
        << p.dump() << ": sd " << st.sd;
    EXPECT_EQ(f.attributes.at("nestlight:ibl_loop_limit_pixels"), "0") << p.dump();
    if (p.at("estimator") == "mis" && p.at("brdf_samples") == 8) sd16 = st.sd;
    if (p.at("estimator") == "mis" && p.at("brdf_samples") == 160) {
      EXPECT_LT(st.sd, sd16 / 3) << "the passes' samples all count";
    }
  }
}

// Visibility: a 2 x 2 m slab 1 m above the floor under a sun texel 45 to 67.5 degrees from the
// zenith, azimuth 0 to 22.5 degrees (texel (0, 2) of a 16 x 8 map). Its rays from a floor point
// reach the slab's height 0.92 to 2.41 m further in +x and 0 to 0.92 m in +y, so the floor at
// x in [-1.85, -1.5], y in [-0.9, 0] (in the camera's view, beside the slab) is in full shadow,
// while everything beyond x = 1.5 sees the whole texel: the closed form of the sun test.
TEST(Ibl, TheMeshesShadowTheSky) {
  test::TempDir t;
  const SunTexel sun(50.0f, 0);
  writeExr(t.file("sun.exr"), sun.map);
  const double lit = sun.radiance;
  for (bool visibility : {true, false}) {
    json p = estimatorParameters("env");
    p["visibility"] = visibility;
    Scene s = floorScene(t, {{"type", "lambert"}, {"base_color", 0.5}}, {{"path", "sun.exr"}}, p,
                         64, true);
    const MethodFrame f = createMethod(s, {true, false})->render(s.camera);
    std::vector<double> shade, open;
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) {
        glm::vec3 q;
        if (!floorPoint(s, x, y, &q)) continue;
        const double r = f.image.get(x, y).r / lit;
        if (q.x > -1.85f && q.x < -1.5f && q.y > -0.9f && q.y < 0.0f) shade.push_back(r);
        if (q.x > 1.5f) open.push_back(r);
      }
    ASSERT_GT(shade.size(), 4u);
    ASSERT_GT(open.size(), 200u);
    // Environment sampling of a lone texel varies only with cos theta across it: the means lie
    // within 4 standard errors of the closed form.
    auto within = [](const std::vector<double>& v) {
      double m = 0, m2 = 0;
      for (double r : v) m += r, m2 += r * r;
      m /= double(v.size());
      const double sd = std::sqrt(std::max(0.0, m2 / double(v.size()) - m * m));
      return std::abs(m - 1) <= 4 * sd / std::sqrt(double(v.size())) + 1e-3;
    };
    EXPECT_TRUE(within(open)) << visibility;
    if (visibility) {
      EXPECT_LT(*std::max_element(shade.begin(), shade.end()), 1e-6) << "the umbra";
    } else {
      EXPECT_TRUE(within(shade)) << "unshadowed";
    }
    EXPECT_EQ(f.attributes.at("nestlight:ibl_bvh_triangles"), "24");
  }
}

// The scan occludes too: a box inside a closed sphere of 20,000 scan points under a sky of 1 sees
// no sky through the points' discs (a pixel may catch a ray between two discs: 2% allowed), and
// all of it (rho L) when visibility is off.
TEST(Ibl, TheScanShadowsTheSky) {
  test::TempDir t;
  buildSphereScan(t, 20000, 1.0f, 128);
  for (bool visibility : {true, false}) {
    Scene s = boxInSphereScene(t, 0.5, "ibl",
                               {{"estimator", "mis"},
                                {"brdf_samples", 8},
                                {"env_samples", 8},
                                {"visibility", visibility}});
    SceneEnvironment e;
    e.constant = Rgb(1.0f);
    s.environment = e;
    const MethodFrame f = createMethod(s, {true, false})->render(s.camera);
    double sum = 0;
    int n = 0;
    for (int y = 8; y < 24; ++y)
      for (int x = 8; x < 24; ++x)
        sum += f.image.get(x, y).r, n++;  // the box's face fills the middle
    if (visibility) {
      EXPECT_LT(sum / n, 0.02 * 0.5) << "light through a closed scan";
      EXPECT_NE(f.attributes.at("nestlight:ibl_scan_hierarchy_nodes"), "0");
    } else {
      EXPECT_NEAR(sum / n, 0.5, 0.02) << "the unoccluded furnace";
    }
  }
}

// A sky of 0.2 with a soft sun: 50 exp(-a^2 / (2 sigma^2)) at angle a from its centre (50 degrees
// from the zenith, sigma 5 degrees), on a 128 x 64 map turned one texel (2.8 degrees) about the
// zenith per frame: a slowly changing probe, as the paper's video sequences are between frames.
HdrImage rotatingSky(int frame, float sun) {
  const int W = 128, H = 64;
  const double sigma = 5 * std::numbers::pi / 180;
  HdrImage img(W, H);
  const double st = std::sin(50 * std::numbers::pi / 180),
               ct = std::cos(50 * std::numbers::pi / 180);
  const double phi0 = 2 * std::numbers::pi * frame / W;
  const glm::dvec3 c(st * std::cos(phi0), st * std::sin(phi0), ct);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const double th = std::numbers::pi * (y + 0.5) / H, ph = 2 * std::numbers::pi * (x + 0.5) / W;
      const glm::dvec3 d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
      const double a = std::acos(std::clamp(glm::dot(c, d), -1.0, 1.0));
      img.set(x, y, Rgb(float(0.2 + sun * std::exp(-a * a / (2 * sigma * sigma)))));
    }
  return img;
}

// Z = integral of L_Y rho_Y cos over the floor's hemisphere (the un-occluded target's mass, eq. 3),
// the same at every floor point: texel by texel, each row's integral of cos over its band.
double trueZ(const HdrImage& img, double rhoY) {
  double z = 0;
  for (int y = 0; y < img.height / 2; ++y) {
    const double c0 = std::cos(std::numbers::pi * y / img.height),
                 c1 = std::cos(std::numbers::pi * (y + 1) / img.height);
    for (int x = 0; x < img.width; ++x)
      z += double(luminance(img.get(x, y))) * (2 * std::numbers::pi / img.width) *
           (c0 * c0 - c1 * c1) / 2;
  }
  return z * rhoY;
}

// SMC over a video light probe: the first frame starts every pixel afresh by BIS; the carried
// normalising constant Z_t (eq. 8) follows the true one while the sun turns, with no
// reinitialisation; when the sun brightens 20-fold (a light switched on) Z_t / Z_t-1 jumps and the
// pixels reinitialise.
TEST(Ibl, SmcTracksTheNormalisingConstantAndReinitialisesOnAJump) {
  test::TempDir t;
  const int frames = 10;
  for (int f = 0; f < frames; ++f)
    writeExr(t.file("sky_" + std::to_string(f) + ".exr"),
             rotatingSky(f, f == frames - 1 ? 1000.0f : 50.0f));
  json p = estimatorParameters("smc");
  p["smc_statistics"] = true;
  p["bis_proposals"] = 256;
  Scene s = floorScene(t, {{"type", "lambert"}, {"base_color", 0.5}},
                       {{"sequence", "sky_%d.exr"}, {"fps", 10}}, p, 24);
  const std::vector<SceneCamera> cameras = sceneCameras(s);
  ASSERT_EQ(cameras.size(), size_t(frames));
  auto m = createMethod(s, {true, false});
  for (int f = 0; f < frames; ++f) {
    const MethodFrame r = m->render(cameras[size_t(f)]);
    const double want =
        trueZ(rotatingSky(f, f == frames - 1 ? 1000.0f : 50.0f), 0.5 / std::numbers::pi);
    const double zMean = std::stod(r.attributes.at("nestlight:ibl_smc_z_mean"));
    const long receivers = std::stol(r.attributes.at("nestlight:ibl_receivers"));
    const long jumps = std::stol(r.attributes.at("nestlight:ibl_smc_reinit_jump"));
    const long fresh = std::stol(r.attributes.at("nestlight:ibl_smc_reinit_new"));
    const long carried = std::stol(r.attributes.at("nestlight:ibl_smc_reprojected"));
    const int bridges = std::stoi(r.attributes.at("nestlight:ibl_smc_bridges"));
    std::printf(
        "frame %d: Z mean %.4f, true %.4f (%.3f); %ld receivers, %ld carried, %ld jumps, %ld "
        "fresh; %d bridges\n",
        f, zMean, want, zMean / want, receivers, carried, jumps, fresh, bridges);
    ASSERT_GT(receivers, 300);
    if (f == 0) {
      EXPECT_EQ(fresh, receivers);
    } else {
      EXPECT_EQ(carried, receivers) << f;
    }
    if (f < frames - 1) {
      // A soft sun turning a tenth of its width's square a frame (chi2 about 0.3) needs no more
      // bridges than the paper's 3 (docs/IBL.md, "How many bridges").
      EXPECT_EQ(bridges, 3) << "frame " << f;
    }
    if (f > 0 && f < frames - 1) {
      EXPECT_EQ(jumps, 0) << "frame " << f << ": no jump while the sun turns";
    }
    if (f == frames - 1) {
      EXPECT_GT(jumps, receivers * 9 / 10) << "the sun brightened 20-fold";
    }
    // Measured: within 1.5% over the 9 turning frames (N = 8, K = 3, M = 256). 5% allows the seed's
    // luck; an SMC whose Z drifted (a reweighting or move that broke invariance) leaves it within
    // a few frames. A hard-edged sun a texel per frame drifts much faster: docs/IBL.md.
    EXPECT_NEAR(zMean / want, 1.0, 0.05) << "frame " << f;
  }
}

// SMC follows the shading point as the camera moves (reprojection): on a still map, a camera
// sliding 2 cm a frame keeps nearly every pixel's samples, reinitialises none on a jump, and Z
// stays the true one.
TEST(Ibl, SmcSamplesFollowAMovingCamera) {
  test::TempDir t;
  writeExr(t.file("sky.exr"), rotatingSky(0, 50.0f));
  json p = estimatorParameters("smc");
  p["smc_statistics"] = true;
  p["bis_proposals"] = 256;
  Scene s = floorScene(t, {{"type", "lambert"}, {"base_color", 0.5}}, {{"path", "sky.exr"}}, p, 24);
  const double want = trueZ(rotatingSky(0, 50.0f), 0.5 / std::numbers::pi);
  auto m = createMethod(s, {true, false});
  for (int f = 0; f < 6; ++f) {
    SceneCamera c = s.camera;
    c.eye.x += 0.02 * f, c.target.x += 0.02 * f;
    const MethodFrame r = m->render(c);
    const long receivers = std::stol(r.attributes.at("nestlight:ibl_receivers"));
    const long carried = std::stol(r.attributes.at("nestlight:ibl_smc_reprojected"));
    const double zMean = std::stod(r.attributes.at("nestlight:ibl_smc_z_mean"));
    if (f > 0) {
      // The pixels a 2 cm step brings in at the image's edge start afresh: one column of 24.
      EXPECT_GT(carried, receivers * 9 / 10) << "frame " << f;
      EXPECT_EQ(r.attributes.at("nestlight:ibl_smc_reinit_jump"), "0") << "frame " << f;
    }
    EXPECT_NEAR(zMean / want, 1.0, 0.05) << "frame " << f;
  }
}

// Frames whose SMC state exceeds one 128 MiB buffer range (1920 x 1080 at 8 samples) are shaded
// in bands of rows, each reading the previous state of the rows about it. Forced down to bands of
// 16 rows at 64 x 64, a still camera gives the same images, bit for bit, as one band.
TEST(Ibl, SmcInBandsOfRowsEqualsOneBand) {
  test::TempDir t;
  writeExr(t.file("sky.exr"), rotatingSky(0, 50.0f));
  std::vector<std::vector<float>> images[2];
  for (int banded = 0; banded < 2; ++banded) {
    json p = estimatorParameters("smc");
    p["bis_proposals"] = 32;
    if (banded) p["smc_band_rows"] = 16;
    Scene s =
        floorScene(t, {{"type", "lambert"}, {"base_color", 0.5}}, {{"path", "sky.exr"}}, p, 64);
    auto m = createMethod(s, {true, false});
    for (int f = 0; f < 3; ++f) {
      const MethodFrame r = m->render(s.camera);
      images[banded].push_back(r.image.rgb);
      if (f > 0) {
        EXPECT_EQ(r.attributes.at("nestlight:ibl_smc_reprojected"),
                  r.attributes.at("nestlight:ibl_receivers"));
      }
    }
  }
  for (int f = 0; f < 3; ++f)
    EXPECT_TRUE(images[0][size_t(f)] == images[1][size_t(f)]) << "frame " << f;
}

// Hard cases: a sun of 1e5 in a sky of 1e-3 stays finite and unbiased for every estimator; an
// all-black frame between bright ones lights nothing (no NaN), and SMC starts afresh after it.
TEST(Ibl, ASunOf1e5AndABlackFrame) {
  test::TempDir t;
  const SunTexel sun(1e5f, 5, 1e-3f);
  writeExr(t.file("sun_0.exr"), sun.map);
  writeExr(t.file("sun_1.exr"), HdrImage(16, 8));  // black
  writeExr(t.file("sun_2.exr"), sun.map);
  const double want = sun.radiance;
  for (const char* e : kEstimators) {
    json p = estimatorParameters(e);
    p["bis_proposals"] = 256;
    p["smc_statistics"] = true;
    Scene s = floorScene(t, {{"type", "lambert"}, {"base_color", 0.5}},
                         {{"sequence", "sun_%d.exr"}, {"fps", 1}}, p);
    const std::vector<SceneCamera> cameras = sceneCameras(s);
    ASSERT_EQ(cameras.size(), 3u);
    auto m = createMethod(s, {true, false});
    for (int f = 0; f < 3; ++f) {
      const MethodFrame r = m->render(cameras[size_t(f)]);
      for (float v : r.image.rgb) ASSERT_TRUE(std::isfinite(v)) << e << " frame " << f;
      const Stats st = ratioStats(s, r, [&](const glm::vec3&) { return f == 1 ? 1.0 : want; });
      if (f == 1) {
        EXPECT_EQ(st.mean, 0.0) << e << ": the black frame";
        continue;
      }
      EXPECT_NEAR(st.mean, 1.0, 4 * st.sd / std::sqrt(double(st.n)) + 2e-3)
          << e << " frame " << f << ": sd " << st.sd;
      if (std::string(e) == "smc" && f == 2) {
        EXPECT_EQ(r.attributes.at("nestlight:ibl_smc_reinit_new"),
                  r.attributes.at("nestlight:ibl_receivers"))
            << "after a black frame no pixel holds samples: all start afresh";
      }
    }
  }
}

// Glossy roughness 0.05 under a high-frequency map (a checkerboard of 1 and 20 in 8 x 8 texel
// squares of a 128 x 64 map): MIS and BIS agree with the reference's direct light, pixel means
// within 4 standard errors of both together.
TEST(Ibl, GlossyUnderAHighFrequencyMapAgreesWithTheReference) {
  test::TempDir t;
  HdrImage img(128, 64);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 128; ++x) img.set(x, y, Rgb(((x / 8 + y / 8) % 2) ? 20.0f : 1.0f));
  writeExr(t.file("checker.exr"), img);
  const json glossy = {
      {"type", "ggx"}, {"base_color", 0.9}, {"roughness", 0.05}, {"metallic", 1.0}};
  Scene ref = floorScene(t, glossy, {{"path", "checker.exr"}}, json::object(), 24);
  ref.gi.method = "direct";
  ref.gi.samplesPerPixel = 256;
  ref.gi.targetRelativeError = 0;
  const MethodFrame truth = createMethod(ref, {true, false})->render(ref.camera);
  for (const char* e : {"mis", "bis"}) {
    json p = estimatorParameters(e);
    p["brdf_samples"] = 32, p["env_samples"] = 32, p["bis_proposals"] = 640, p["bis_samples"] = 32;
    Scene s = floorScene(t, glossy, {{"path", "checker.exr"}}, p, 24);
    const MethodFrame f = createMethod(s, {true, false})->render(s.camera);
    double sum = 0, sumRef = 0, d2 = 0;
    int n = 0;
    for (int y = 0; y < 24; ++y)
      for (int x = 0; x < 24; ++x) {
        glm::vec3 q;
        if (!floorPoint(s, x, y, &q)) continue;
        const double a = f.image.get(x, y).r, b = truth.image.get(x, y).r;
        sum += a, sumRef += b, d2 += (a - b) * (a - b), n++;
      }
    ASSERT_GT(n, 200);
    const double meanDiff = (sum - sumRef) / n, sdDiff = std::sqrt(d2 / n - meanDiff * meanDiff);
    EXPECT_NEAR(meanDiff, 0.0, 4 * sdDiff / std::sqrt(double(n)) + 1e-3 * sumRef / n)
        << e << ": mean " << sum / n << " against " << sumRef / n;
  }
}

// A damaged frame of a probe sequence: an error naming it, or (on_bad_frame "previous") the last
// good frame lights again.
TEST(Ibl, ADamagedProbeFrameIsNamedOrThePreviousKept) {
  test::TempDir t;
  writeExr(t.file("p_0.exr"), rotatingSky(0, 50.0f));
  test::writeFile(t.file("p_1.exr"), "not an exr");
  for (bool keep : {false, true}) {
    json env = {{"sequence", "p_%d.exr"}, {"fps", 1}};
    if (keep) env["on_bad_frame"] = "previous";
    Scene s = floorScene(t, {{"type", "lambert"}, {"base_color", 0.5}}, env,
                         estimatorParameters("mis"), 16);
    const std::vector<SceneCamera> cameras = sceneCameras(s);
    ASSERT_EQ(cameras.size(), 2u);
    auto m = createMethod(s, {true, false});
    const MethodFrame first = m->render(cameras[0]);
    if (!keep) {
      const Error err = test::errorOf([&] { m->render(cameras[1]); });
      EXPECT_NE(std::string(err.what()).find("p_1.exr"), std::string::npos) << err.what();
    } else {
      const MethodFrame second = m->render(cameras[1]);
      EXPECT_EQ(second.attributes.at("nestlight:environment_frame"), "1");
      double a = 0, b = 0;
      for (size_t i = 0; i < first.image.rgb.size(); ++i)
        a += first.image.rgb[i], b += second.image.rgb[i];
      // The same map sampled again with the next frame's random numbers: 5% of the image's light.
      EXPECT_NEAR(b / a, 1.0, 0.05) << "the previous frame's light";
    }
  }
}

// `nestlight bench ibl` end to end at a toy size: a row per estimator, sample count and frame,
// and the summary's times to 5% and 2%; the scanned scene at a toy size.
TEST(Ibl, BenchIblWritesItsTablesAndPlots) {
  test::TempDir t;
  std::string out;
  const int rc = test::runCli(
      "bench ibl --scenes moving-sun --frames 2 --size 16 --timing-size 0 --samples 1,2 "
      "--reference-spp 4 --no-variance -o " +
          t.path().string(),
      &out);
  ASSERT_EQ(rc, 0) << out;
  std::ifstream csv(t.path() / "bench_ibl.csv");
  std::string line;
  int rows = -1;
  while (std::getline(csv, line)) rows++;
  EXPECT_EQ(rows, 4 * 2 * 2) << "estimators x sample counts x frames";
  std::ifstream js(t.path() / "bench_ibl.json");
  const json j = json::parse(js);
  ASSERT_EQ(j.at("scenes").size(), 1u);
  for (const auto& e : j.at("scenes")[0].at("estimators")) {
    EXPECT_TRUE(e.contains("time_to_5pct")) << e.dump();
    EXPECT_EQ(e.at("levels").size(), 2u);
  }
  EXPECT_TRUE(std::filesystem::exists(t.path() / "moving-sun_speed.svg"));
  EXPECT_TRUE(std::filesystem::exists(t.path() / "moving-sun_frames.svg"));
  // Scanned receivers (the object scene's town in the albedo mode): errors on 4 x 4 block means
  // and the image mean's ratio too, as there the per-pixel error has the splats' colours as a
  // floor. A wiring check: at 16 x 16 pixels and 16 samples (the reference's too) the town's mean
  // is 0.94 of the reference's, noisy; a block or ratio computed over the wrong pixels lands far
  // off.
  const int scanned = test::runCli(
      "bench ibl --scenes scanned --estimators mis --frames 2 --size 16 --timing-size 0 "
      "--samples 16 --reference-spp 16 --no-variance -o " +
          (t.path() / "scan").string(),
      &out);
  ASSERT_EQ(scanned, 0) << out;
  const json js2 = json::parse(std::ifstream(t.path() / "scan" / "bench_ibl.json"));
  const json& level = js2.at("scenes").at(0).at("estimators").at(0).at("levels").at(0);
  EXPECT_NEAR(level.at("median_mean_ratio").get<double>(), 1.0, 0.25) << level.dump();
  EXPECT_TRUE(level.contains("median_relative_l2_4x4")) << level.dump();
  const int bad =
      test::runCli("bench ibl --estimators mis,foo --frames 2 -o " + t.path().string(), &out);
  EXPECT_NE(bad, 0);
  EXPECT_NE(out.find("foo"), std::string::npos) << out;
}

// A map with NaN, infinite or negative texels lights the GL methods as the path tracer (those
// texels black), and they say so as it does, once, instead of silently.
TEST(Ibl, ABadEnvironmentMapIsAWarningInEveryGlMethod) {
  test::TempDir t;
  TestSceneOptions o;
  o.points = 5000;
  o.width = 16;
  o.height = 12;
  o.quiet = true;
  const auto file = makeTestScene(TestSceneKind::Cornell, t.path() / "room", o);
  HdrImage env(8, 4);
  for (auto& v : env.rgb) v = 0.5f;
  env.rgb[0] = std::nanf("");
  env.rgb[4] = -1.0f;
  env.rgb[8] = INFINITY;
  writeExr(t.file("sky.exr"), env);
  json scene = json::parse(std::ifstream(file));
  scene["environment"] = {{"path", t.file("sky.exr")}};
  std::ofstream(t.file("room/sky.json")) << scene.dump(1);
  for (const char* method : {"raster", "vpl"}) {
    std::string out;
    ASSERT_EQ(test::runCli(std::string("render ") + t.file("room/sky.json") + " --method " +
                               method + " -o " + t.file("o.exr"),
                           &out),
              0)
        << out;
    EXPECT_NE(out.find("sky.exr: environment: 3 NaN, infinite or negative texels set to 0"),
              std::string::npos)
        << method << ": " << out;
  }
}

}  // namespace
}  // namespace nestlight::gi
