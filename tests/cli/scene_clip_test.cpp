// Clipping volumes in GI scenes (octrees[].clipping): what they remove is not part of the scene for
// the GL frame (raster) nor the path tracer (reference). A box that removes the whole scan gives
// the image of the scene without it, and a bad volume names its field.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "nestlight/gi/hdr_image.h"
#include "test_support.h"

namespace scene_clip_test {

using nestlight::test::runCli;
using nestlight::test::TempDir;

nlohmann::json cornell(const TempDir& dir) {
  std::string out;
  EXPECT_EQ(runCli("make-scene cornell -q -n 20k --width 32 --height 24 -o " + dir.file("c"), &out),
            0)
      << out;
  std::ifstream f(dir.file("c/scene.json"));
  nlohmann::json j = nlohmann::json::parse(f);
  // A fixed frame origin, so the scenes with and without the scan share their float frame.
  j["origin"] = {2.0, 2.0, 1.5};
  return j;
}

nestlight::gi::HdrImage render(const TempDir& dir, const nlohmann::json& scene,
                               const std::string& name, const std::string& method) {
  nestlight::test::writeFile(dir.file("c/" + name + ".json"), scene.dump());
  std::string out;
  EXPECT_EQ(runCli("render " + dir.file("c/" + name + ".json") + " --method " + method +
                       " --spp 4 -o " + dir.file(name + ".exr"),
                   &out),
            0)
      << out;
  return nestlight::gi::readHdrImage(dir.file(name + ".exr"));
}

double meanAbsDifference(const nestlight::gi::HdrImage& a, const nestlight::gi::HdrImage& b) {
  EXPECT_EQ(a.rgb.size(), b.rgb.size());
  double d = 0, s = 0;
  for (size_t i = 0; i < a.rgb.size() && i < b.rgb.size(); ++i)
    d += std::abs(a.rgb[i] - b.rgb[i]), s += std::abs(b.rgb[i]);
  return d / std::max(s, 1e-12);
}

class SceneClip : public ::testing::TestWithParam<const char*> {};

TEST_P(SceneClip, ABoxRemovingTheScanGivesTheSceneWithoutIt) {
  nestlight::test::noLeakChecksInGlChildren();
  TempDir dir;
  nlohmann::json scene = cornell(dir);
  const auto whole = render(dir, scene, "whole", GetParam());
  nlohmann::json without = scene;
  without["octrees"] = nlohmann::json::array();
  const auto none = render(dir, without, "none", GetParam());
  scene["octrees"][0]["clipping"] = {
      {{"type", "box"}, {"center", {100.0, 100.0, 100.0}}, {"size", {1.0, 1.0, 1.0}}}};
  const auto clipped = render(dir, scene, "clipped", GetParam());
  // The room is the scan: without it the sphere floats in the dark, and clipping it all away is
  // the same picture. The path tracer draws the same samples (its seeds do not depend on the
  // scan); the GL frame fits its clip planes and lights' views to every object's bounds, the
  // clipped scan's included, so depth-dependent biases move by a hair (3.5e-4 measured).
  EXPECT_GT(meanAbsDifference(whole, none), 0.3);
  EXPECT_LT(meanAbsDifference(clipped, none), std::string(GetParam()) == "raster" ? 2e-3 : 1e-6);
}

INSTANTIATE_TEST_SUITE_P(Methods, SceneClip, ::testing::Values("raster", "reference"));

TEST(SceneClip, ACrossingPolygonNamesItsField) {
  TempDir dir;
  nlohmann::json scene = cornell(dir);
  scene["octrees"][0]["clipping"] = {
      {{"type", "polygon"}, {"points", {{0, 0}, {1, 1}, {1, 0}, {0, 1}}}}};
  nestlight::test::writeFile(dir.file("c/bad.json"), scene.dump());
  std::string out;
  EXPECT_EQ(
      runCli("render " + dir.file("c/bad.json") + " --method raster -o " + dir.file("bad.exr"),
             &out),
      1);
  EXPECT_NE(out.find("octrees[0]"), std::string::npos) << out;
  EXPECT_NE(out.find("crosses itself"), std::string::npos) << out;
}

}  // namespace scene_clip_test
