// `nestlight bake-radiance`: the captured radiance of an albedo-mode scene's points, written as a
// colour layer the octree reader opens; scenes whose colours are radiance already are refused.
#include <gtest/gtest.h>

#include <cmath>

#include "nestlight/gi/scene.h"
#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/octree_reader.h"
#include "test_support.h"

using namespace nestlight;

namespace {

// make-scene `kind` into dir/kind, small.
std::string makeScene(const test::TempDir& dir, const std::string& kind) {
  std::string out;
  EXPECT_EQ(
      test::runCli("make-scene " + kind + " -q -n 4k --width 16 --height 12 -o " + dir.file(kind),
                   &out),
      0)
      << out;
  return dir.file(kind) + "/scene.json";
}

TEST(BakeRadianceCli, WritesALayerTheReaderOpens) {
  test::TempDir dir;
  const std::string scene = makeScene(dir, "object");  // albedo mode: a sky, a sun, a torus
  std::string out;
  ASSERT_EQ(
      test::runCli("bake-radiance " + scene + " --layer captured --spp 4 --bounces 2 -q", &out), 0)
      << out;
  EXPECT_NE(out.find("std. error"), std::string::npos) << out;
  EXPECT_NE(out.find("1 inserted mesh"), std::string::npos) << out;  // the torus
  const gi::Scene s = gi::loadScene(scene);
  OctreeReader r(s.octrees[0].path);
  const ColourLayerReader layer(s.octrees[0].path, r.metadata(), "captured");
  EXPECT_EQ(layer.record().points, r.metadata().points);
  EXPECT_EQ(layer.record().build.at("max_bounces").get<int>(), 2);
  // Sunlit and under a sky, most points send light out, and none sends NaN or less than 0.
  uint64_t lit = 0, total = 0;
  for (const auto& [key, e] : r.allNodes()) {
    if (e.numPoints == 0) continue;
    const std::vector<float> rgb = layer.readNode(key, e.numPoints);
    for (size_t i = 0; i < e.numPoints; ++i) {
      const float v = rgb[3 * i] + rgb[3 * i + 1] + rgb[3 * i + 2];
      ASSERT_TRUE(std::isfinite(v) && v >= 0) << i;
      lit += v > 0;
      ++total;
    }
  }
  EXPECT_GT(lit, total / 2);
  // The example in --help names the command's real options.
  ASSERT_EQ(test::runCli("bake-radiance --help", &out), 0);
  EXPECT_NE(out.find("--layer captured"), std::string::npos) << out;
}

TEST(BakeRadianceCli, RefusesRadianceCacheScenesAndReservedNames) {
  test::TempDir dir;
  const std::string cornell = makeScene(dir, "cornell");  // radiance-cache mode
  std::string out;
  EXPECT_EQ(test::runCli("bake-radiance " + cornell + " --layer captured -q", &out), 1) << out;
  EXPECT_NE(out.find("gi.mode"), std::string::npos) << out;
  EXPECT_NE(out.find("albedo mode"), std::string::npos) << out;
  const std::string object = makeScene(dir, "object");
  EXPECT_EQ(test::runCli("bake-radiance " + object + " --layer rgb -q", &out), 1) << out;
  EXPECT_NE(out.find("'rgb'"), std::string::npos) << out;
  EXPECT_EQ(test::runCli("bake-radiance " + object + " --layer captured --spp 1 -q", &out), 1)
      << out;
}

}  // namespace
