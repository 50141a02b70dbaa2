// The reference's scan surfaces are closed for rays whatever the sampling (issue 30): a closed
// box sampled at random or in a scanner's stripes lets no ray out, and the generated cornell
// room, randomly sampled, shows no black speckle where camera rays slipped between discs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "nestlight/converters/test_scenes.h"
#include "nestlight/gi/reference/path_tracer.h"
#include "test_support.h"

namespace {

enum class BoxSampling { Random, Stripes };

// Points on the six faces of the unit box, normals facing inwards, with Gaussian noise of
// `noise` along the normal. Random: uniform by area. Stripes: lines of points a apart (10%
// jitter), the gap between lines drawn uniformly from a to 3a, as a scanner's lines fall on a
// wall seen at an angle; each face's lines run along one of its axes.
nestlight::gi::DiscCloud sampledBox(BoxSampling how, int points, uint64_t seed, float noise) {
  nestlight::gi::Rng rng(seed);
  nestlight::gi::DiscCloud c;
  auto add = [&](int face, float u, float v) {
    const int axis = face / 2;
    const float side = float(face % 2);
    glm::vec3 p, n(0.0f);
    p[axis] = side;
    p[(axis + 1) % 3] = u;
    p[(axis + 2) % 3] = v;
    n[axis] = side > 0 ? -1.0f : 1.0f;
    const glm::vec2 g = rng.uniform2();
    const float gauss =
        std::sqrt(-2 * std::log(std::max(g.x, 1e-12f))) * std::cos(2 * nestlight::gi::kPi * g.y);
    c.discs.emplace_back(p + n * noise * gauss, 0.0f);
    c.normals.push_back(n);
    c.colour.emplace_back(1.0f);
  };
  if (how == BoxSampling::Random) {
    for (int i = 0; i < points; ++i) {
      const int face = std::min(5, int(rng.uniform() * 6));
      const glm::vec2 uv = rng.uniform2();
      add(face, uv.x, uv.y);
    }
    return c;
  }
  // Lines a apart on average across, points a apart along: 1 / (2 a^2) points per unit area.
  const float a = std::sqrt(6.0f / (2.0f * points));
  for (int face = 0; face < 6; ++face) {
    const bool alongU = face % 3 != 1;
    for (float across = rng.uniform() * a; across < 1; across += a * (1 + 2 * rng.uniform()))
      for (float along = rng.uniform() * a; along < 1; along += a * (0.9f + 0.2f * rng.uniform())) {
        const float x = std::clamp(across + 0.1f * a * (rng.uniform() - 0.5f), 0.0f, 1.0f);
        alongU ? add(face, along, x) : add(face, x, along);
      }
  }
  return c;
}

// Rays from points uniformly inside the box (2 cm off its walls, so many meet a wall at a
// grazing angle), in uniformly random directions, that meet no disc.
int escapingRays(nestlight::gi::DiscCloud cloud, float radiusScale, int rays, uint64_t seed) {
  nestlight::gi::assignDiscRadii(cloud, radiusScale);
  nestlight::gi::ReferenceScene s({std::move(cloud)}, {}, {}, {}, {},
                                  nestlight::gi::EnvironmentMap());
  nestlight::gi::Rng rng(seed);
  int escaped = 0;
  for (int i = 0; i < rays; ++i) {
    nestlight::gi::SurfaceHit h;
    const glm::vec3 o =
        glm::vec3(0.02f) + 0.96f * glm::vec3(rng.uniform(), rng.uniform(), rng.uniform());
    escaped += !s.intersect(o, nestlight::gi::sampleUniformSphere(rng.uniform2()), INFINITY, &h);
  }
  return escaped;
}

void expectClosed(BoxSampling how) {
  // 60,000 points: 1 cm spacing, as the generated cornell room at 1 M points; noise 0 and 1 mm,
  // the room's. The rule of model version 3 (1.5 x half the 8th-neighbour distance) let 470 to
  // 560 of these rays out of the random box. At 0.8 x the radii, each disc covers less than its
  // cell on a noiseless surface and rays pass at the cells' corners: the test can fail.
  for (float noise : {0.0f, 0.001f}) {
    const int escaped = escapingRays(sampledBox(how, 60000, 5, noise), 1.0f, 200000, 7);
    std::printf("noise %.0f mm: %d of 200000 rays escaped\n", noise * 1000, escaped);
    EXPECT_EQ(escaped, 0) << "noise " << noise;
  }
  EXPECT_GT(escapingRays(sampledBox(how, 60000, 5, 0.0f), 0.8f, 200000, 7), 0);
  // A scan without normals: planes fitted to the neighbours, discs facing each ray.
  nestlight::gi::DiscCloud noNormals = sampledBox(how, 60000, 5, 0.001f);
  noNormals.normals.clear();
  EXPECT_EQ(escapingRays(std::move(noNormals), 1.0f, 200000, 7), 0) << "without normals";
}

}  // namespace

TEST(Watertight, RandomlySampledBoxLeaksNoRay) {
  expectClosed(BoxSampling::Random);
}

TEST(Watertight, ScannerStripedBoxLeaksNoRay) {
  expectClosed(BoxSampling::Stripes);
}

TEST(Watertight, CornellRoomShowsNoBlackSpeckle) {
  // The generated room (random points, 1 mm noise) path traced in radiance-cache mode, where
  // a camera ray that meets no disc leaves the closed room and returns black. 200,000 points
  // (2 cm spacing), 64 x 64 pixels.
  nestlight::test::TempDir t;
  nestlight::TestSceneOptions so;
  so.points = 200'000;
  so.width = 64;
  so.height = 64;
  so.quiet = true;
  nestlight::gi::Scene scene = nestlight::gi::loadScene(
      nestlight::makeTestScene(nestlight::TestSceneKind::Cornell, t.path() / "cornell", so));
  // Camera rays that find no surface, of 16 jittered rays a pixel.
  auto escapingCameraRays = [&](const nestlight::gi::ReferenceScene& rs) {
    nestlight::gi::Rng rng(3);
    int escaped = 0;
    for (int y = 0; y < so.height; ++y)
      for (int x = 0; x < so.width; ++x)
        for (int k = 0; k < 16; ++k) {
          const glm::vec2 j = rng.uniform2();
          glm::vec3 ro, rd;
          nestlight::gi::cameraRay(scene.camera, rs.origin(), x + j.x, y + j.y, &ro, &rd);
          nestlight::gi::SurfaceHit h;
          escaped += !rs.intersect(ro, rd, INFINITY, &h);
        }
    return escaped;
  };
  // Discs 0.7 times as wide leave gaps (the count can fail).
  scene.octrees[0].radiusScale = 0.7f;
  EXPECT_GT(escapingCameraRays(*nestlight::gi::ReferenceScene::load(scene)), 0);
  scene.octrees[0].radiusScale = 1.0f;
  const auto rs = nestlight::gi::ReferenceScene::load(scene);
  EXPECT_EQ(escapingCameraRays(*rs), 0) << "of " << 16 * so.width * so.height << " camera rays";
  // No isolated black pixel: luminance below 5% of the median of its 8 neighbours (the room's
  // darkest wall is 4 times dimmer than its brightest, far from 5%; noise at 8 samples a pixel
  // varies a pixel by tens of per cent, not by 20 times).
  nestlight::gi::ReferenceOptions o = nestlight::gi::referenceOptionsFrom(scene.gi);
  o.targetRelativeError = 0;
  o.maxSamplesPerPixel = 8;
  const nestlight::gi::HdrImage img = nestlight::gi::renderReference(*rs, scene.camera, o).image;
  auto lum = [&](int x, int y) {
    const nestlight::gi::Rgb c = img.get(x, y);
    return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b;
  };
  int speckles = 0;
  for (int y = 1; y + 1 < img.height; ++y)
    for (int x = 1; x + 1 < img.width; ++x) {
      float around[8];
      int m = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          if (dx || dy) around[m++] = lum(x + dx, y + dy);
      std::nth_element(around, around + 4, around + 8);
      speckles += lum(x, y) < 0.05f * around[4];
    }
  EXPECT_EQ(speckles, 0);
}

namespace {

// Two bunches of a few returns 0.4 m apart, 0.5 m above a randomly sampled 1 m plane at 1 cm
// spacing (the lion's scan has two such above its head): each bunch's discs are sized by the
// bunch, not by the gap to the other. Measured: the widest 4.4 cm (the outlier cap, 3 x the
// bunch's own spacing); without the bunch rule 0.49 m. The plane's discs keep their size (mean
// 1.24 spacings; bounds 1 to 2).
TEST(Watertight, StrayBunchesDrawAsSmallDiscs) {
  nestlight::gi::Rng rng(11);
  nestlight::gi::DiscCloud c;
  for (int i = 0; i < 10000; ++i) {
    const glm::vec2 uv = rng.uniform2();
    c.discs.emplace_back(uv.x, uv.y, 0.0f, 0.0f);
    c.normals.emplace_back(0.0f, 0.0f, 1.0f);
  }
  const size_t plane = c.discs.size();
  for (const auto& [centre, n] :
       {std::pair{glm::vec3(0.3f, 0.5f, 0.5f), 4}, std::pair{glm::vec3(0.7f, 0.5f, 0.5f), 6}})
    for (int i = 0; i < n; ++i) {
      const glm::vec3 jitter = glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) - 0.5f;
      c.discs.emplace_back(centre + 0.01f * jitter, 0.0f);
      c.normals.emplace_back(0.0f, 0.0f, 1.0f);
    }
  nestlight::gi::assignDiscRadii(c, 1.0f);
  double planeSum = 0;
  for (size_t i = 0; i < plane; ++i) planeSum += c.discs[i].w;
  const double planeMean = planeSum / double(plane);
  EXPECT_GT(planeMean, 0.01);
  EXPECT_LT(planeMean, 0.02);
  float widest = 0;
  for (size_t i = plane; i < c.discs.size(); ++i) {
    EXPECT_LT(c.discs[i].w, 0.05f) << "bunch point " << i - plane;
    widest = std::max(widest, c.discs[i].w);
  }
  std::printf("plane's mean disc radius %.4f, the bunches' widest %.4f\n", planeMean, widest);
}

}  // namespace
