// The baked capture against the answer a Lambertian plane under a uniform sky has, rho L (the sky
// fills its hemisphere and nothing else does), and the rule that inserted meshes are left out of
// the capture while meshes of the captured scene ("inserted": false) stay in it.
#include "nestlight/gi/reference/bake_radiance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "gi/floor_scene.h"
#include "nestlight/converters/test_scenes.h"
#include "nestlight/gi/sampling.h"
#include "nestlight/gi/srgb.h"
#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/octree_reader.h"
#include "test_support.h"

using namespace nestlight;
using namespace nestlight::gi;
using json = nlohmann::json;

namespace {

constexpr int kGrey = 188;    // the floor's recorded colour: albedo srgbDecode(188 / 255) ~ 0.50
constexpr float kSky = 2.0f;  // the sky's radiance
constexpr int kSpp = 32;
constexpr float kHalf = 2.0f;  // the floor spans [-2, 2]^2

// 45 x 45 jittered points of a 4 x 4 m floor at z = 0, normals up.
void buildFloor(const test::TempDir& t) {
  std::vector<ScanPoint> points;
  const int n = 45;
  Rng rng(7);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const glm::vec2 u = rng.uniform2();
      const float x = -kHalf + (i + u.x) * 2 * kHalf / n, y = -kHalf + (j + u.y) * 2 * kHalf / n;
      points.push_back({{x, y, 0}, {0, 0, 1}, kGrey, kGrey, kGrey});
    }
  writeScanPly(t.file("floor.ply"), points);
  test::buildOctreeFrom(t.file("floor.ply"), t.path() / "floor.octree");
  writeBoxObj(t.path() / "box.obj");
}

// The floor under the sky; with `box`, a 1 x 1 x 0.2 m box 0.3 m above its centre, inserted or
// part of the captured scene.
Scene floorScene(const test::TempDir& t, const char* mode, std::optional<bool> boxInserted) {
  json j = {{"version", 1},
            {"origin", {0.0, 0.0, 0.0}},
            {"octrees", {{{"path", "floor.octree"}}}},
            {"environment", {{"constant", kSky}}},
            {"materials", {{"grey", {{"type", "lambert"}, {"base_color", 0.5}}}}},
            {"gi", {{"mode", mode}, {"seed", 3}, {"max_bounces", 3}}}};
  if (boxInserted)
    j["meshes"] = {{{"path", "box.obj"},
                    {"transform", {{"translate", {-0.5, -0.5, 0.3}}, {"scale", {1.0, 1.0, 0.2}}}},
                    {"material", "grey"},
                    {"inserted", *boxInserted}}};
  std::ofstream(t.file("scene.json")) << j.dump(2);
  return loadScene(t.file("scene.json"));
}

struct BakedPoint {
  glm::dvec3 position;
  float value;  // the channel mean
};

std::vector<BakedPoint> readLayer(const std::filesystem::path& dir, const std::string& name) {
  OctreeReader r(dir);
  const Metadata& m = r.metadata();
  ColourLayerReader layer(dir, m, name);
  std::vector<BakedPoint> out;
  for (const auto& [key, e] : r.allNodes()) {
    if (e.numPoints == 0) continue;
    const PointBuffer pts = r.readNode(key);
    const std::vector<float> rgb = layer.readNode(key, e.numPoints);
    for (size_t i = 0; i < pts.size(); ++i) {
      const glm::dvec3 p = glm::dvec3(m.offset.x, m.offset.y, m.offset.z) +
                           glm::dvec3(pts.pos[3 * i], pts.pos[3 * i + 1], pts.pos[3 * i + 2]) *
                               glm::dvec3(m.scale.x, m.scale.y, m.scale.z);
      out.push_back({p, (rgb[3 * i] + rgb[3 * i + 1] + rgb[3 * i + 2]) / 3});
    }
  }
  return out;
}

RadianceBakeOptions options(const std::string& layer) {
  RadianceBakeOptions o;
  o.layer = layer;
  o.samplesPerPoint = kSpp;
  o.maxBounces = 3;
  o.seed = 3;
  return o;
}

TEST(BakeRadiance, LambertFloorUnderUniformSkyIsRhoTimesL) {
  test::TempDir t;
  buildFloor(t);
  const RadianceBakeReport rep = bakeRadiance(floorScene(t, "albedo", {}), options("captured"));
  const double want = srgbDecode(kGrey / 255.0f) * kSky;
  const auto pts = readLayer(t.path() / "floor.octree", "captured");
  ASSERT_EQ(pts.size(), 45u * 45u);
  EXPECT_EQ(rep.points, pts.size());
  EXPECT_EQ(rep.blackPoints, 0u);
  EXPECT_EQ(rep.nonFiniteSamples, 0u);
  // Every estimate of the sky has variance (MIS between sky and BSDF samples), yet a small one.
  EXPECT_GT(rep.meanRelativeStandardError, 0.0);
  EXPECT_LT(rep.meanRelativeStandardError, 0.2);
  double sum = 0, worst = 0;
  for (const auto& p : pts) {
    sum += p.value;
    worst = std::max(worst, std::abs(p.value / want - 1));
  }
  const double mean = sum / double(pts.size());
  std::printf("rho L %.4f: mean %.4f, worst point %.3f off, mean relative SE %.4f\n", want, mean,
              worst, rep.meanRelativeStandardError);
  // The points' estimates are independent: their mean's relative error is about the points'
  // relative standard error over sqrt(points); 4 of those (the sky's estimator is unbiased).
  EXPECT_NEAR(mean / want, 1.0, 4 * rep.meanRelativeStandardError / std::sqrt(double(pts.size())));
  // Each point: a mean of 32 bounded samples, within 6 of its standard errors.
  EXPECT_LT(worst, 6 * rep.meanRelativeStandardError);
  // The layer records how it was made and its error.
  OctreeReader r(t.path() / "floor.octree");
  const ColourLayerReader layer(t.path() / "floor.octree", r.metadata(), "captured");
  const json& build = layer.record().build;
  EXPECT_DOUBLE_EQ(build.at("mean_relative_standard_error").get<double>(),
                   rep.meanRelativeStandardError);
  EXPECT_EQ(build.at("samples_per_point").get<int>(), kSpp);
}

TEST(BakeRadiance, InsertedMeshesAreLeftOutCapturedOnesStay) {
  test::TempDir t;
  buildFloor(t);
  const std::filesystem::path oct = t.path() / "floor.octree";
  bakeRadiance(floorScene(t, "albedo", {}), options("bare"));
  const RadianceBakeReport inserted =
      bakeRadiance(floorScene(t, "albedo", true), options("inserted"));
  const RadianceBakeReport captured =
      bakeRadiance(floorScene(t, "albedo", false), options("captured"));
  EXPECT_EQ(inserted.meshesLeftOut, 1u);
  EXPECT_EQ(captured.meshesLeftOut, 0u);
  const auto bare = readLayer(oct, "bare"), withInserted = readLayer(oct, "inserted"),
             withCaptured = readLayer(oct, "captured");
  ASSERT_EQ(bare.size(), withInserted.size());
  ASSERT_EQ(bare.size(), withCaptured.size());
  // Left out, the box changes nothing: the same scene and seed trace the same paths.
  for (size_t i = 0; i < bare.size(); ++i) ASSERT_EQ(bare[i].value, withInserted[i].value) << i;
  // Kept, it shades the floor under it: from its centre its bottom face (0.3 m up, 1 m wide)
  // covers about R^2 / (R^2 + h^2) ~ 0.75 of the cosine-weighted sky; what it sends down is the
  // floor's light reflected again (albedo 0.5 x 0.5). Under its middle (|x|, |y| < 0.25) the
  // floor keeps well under 70% of its open-sky radiance.
  double under = 0, underOpen = 0;
  int n = 0;
  for (size_t i = 0; i < bare.size(); ++i)
    if (std::abs(bare[i].position.x) < 0.25 && std::abs(bare[i].position.y) < 0.25) {
      under += withCaptured[i].value;
      underOpen += bare[i].value;
      ++n;
    }
  ASSERT_GT(n, 20);
  std::printf("under the box: %.4f of the open sky's %.4f (%d points)\n", under / n, underOpen / n,
              n);
  EXPECT_LT(under, 0.7 * underOpen);
  EXPECT_GT(under, 0.0);  // the sky still reaches them from the sides
}

TEST(BakeRadiance, UserErrorsNameTheField) {
  test::TempDir t;
  buildFloor(t);
  const Error cache =
      test::errorOf([&] { bakeRadiance(floorScene(t, "radiance_cache", {}), options("c")); });
  EXPECT_EQ(cache.position(), "gi.mode");
  EXPECT_NE(cache.reason().find("albedo"), std::string::npos) << cache.what();
  const Error rgb =
      test::errorOf([&] { bakeRadiance(floorScene(t, "albedo", {}), options("rgb")); });
  EXPECT_NE(rgb.reason().find("rgb"), std::string::npos) << rgb.what();
  Scene noScans = floorScene(t, "albedo", {});
  noScans.octrees.clear();
  EXPECT_EQ(test::errorOf([&] { bakeRadiance(noScans, options("c")); }).position(), "octrees");
  // Baking over the layer the albedos come from would lose them.
  Scene fromLayer = floorScene(t, "albedo", {});
  bakeRadiance(fromLayer, options("albedo"));
  fromLayer.octrees[0].colour = "albedo";
  EXPECT_EQ(test::errorOf([&] { bakeRadiance(fromLayer, options("albedo")); }).position(),
            "octrees[0].colour");
  RadianceBakeOptions one = options("c");
  one.samplesPerPoint = 1;
  EXPECT_NE(test::errorOf([&] { bakeRadiance(floorScene(t, "albedo", {}), one); }).what(),
            std::string());
}

}  // namespace
