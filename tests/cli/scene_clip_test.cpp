// Clipping volumes in GI scenes (octrees[].clipping): what they remove is not part of the scene for
// the GL frame (raster), the GI methods that gather from the scan (vpl, pbgi, projection) nor the
// path tracer (reference). A box that removes the whole scan gives the image of the scene without
// it, and a bad volume names its field.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "nestlight/gi/hdr_image.h"
#include "nestlight/viewer/image.h"
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
  const std::string method = GetParam();
  const auto whole = render(dir, scene, "whole", method);
  nlohmann::json without = scene;
  without["octrees"] = nlohmann::json::array();
  const auto none = render(dir, without, "none", method);
  // Far from the scan: every node is removed whole (the streamer never loads one).
  scene["octrees"][0]["clipping"] = {
      {{"type", "box"}, {"center", {100.0, 100.0, 100.0}}, {"size", {1.0, 1.0, 1.0}}}};
  const auto far = render(dir, scene, "far", method);
  // In the room's air: the box cuts through the scan's one node (its cube holds the whole room)
  // but holds none of its points, so every point is removed one by one: on the GPU in the
  // frame's rasterisers and in what the GI methods gather light from (vpl's ISM pool,
  // projection's point set, pbgi's hierarchies), at load in the path tracer.
  scene["octrees"][0]["clipping"] = {
      {{"type", "box"}, {"center", {1.0, 1.0, 3.0}}, {"size", {1.0, 1.0, 1.0}}}};
  nestlight::test::writeFile(dir.file("air_clip.json"),
                             nlohmann::json{{"clipping", scene["octrees"][0]["clipping"]}}.dump());
  std::string info;
  EXPECT_EQ(
      runCli("info " + dir.file("c/scan.octree") + " --clip " + dir.file("air_clip.json"), &info),
      0);
  EXPECT_NE(info.find("0 points kept (1 nodes tested point by point"), std::string::npos) << info;
  const auto air = render(dir, scene, "air", method);
  // The room is the scan: without it the sphere floats in the dark, and clipping it all away is
  // the same picture. The path tracer draws the same samples (its seeds do not depend on the
  // scan); the GL frame fits its clip planes and lights' views to every object's bounds, the
  // clipped scan's included, so depth-dependent biases move by a hair (3.5e-4 measured).
  EXPECT_GT(meanAbsDifference(whole, none), 0.3);
  const double tolerance = method == "reference" ? 1e-6 : 2e-3;
  EXPECT_LT(meanAbsDifference(far, none), tolerance);
  EXPECT_LT(meanAbsDifference(air, none), tolerance);
}

INSTANTIATE_TEST_SUITE_P(Methods, SceneClip,
                         ::testing::Values("raster", "vpl", "pbgi", "projection", "reference"));

// `render scene.json --state`: the state's camera, GI method, parameters and clipping volumes
// render what the scene file with those fields renders; its annotation is drawn over the PNG only.
TEST(SceneState, AStateSetsTheScenesCameraMethodParametersAndClipping) {
  nestlight::test::noLeakChecksInGlChildren();
  TempDir dir;
  nlohmann::json scene = cornell(dir);
  const nlohmann::json clipping = {{{"type", "box"},
                                    {"center", {2.0, 2.0, 0.0}},
                                    {"size", {4.5, 4.5, 1.0}},
                                    {"mode", "outside"}}};
  const nlohmann::json state = {
      {"camera", {{"eye", {3.6, 0.4, 2.8}}, {"target", {2.0, 2.2, 1.0}}, {"fov", 60}}},
      {"gi", {{"method", "raster"}, {"parameters", {{"splat_scale", 1.5}}}}},
      {"clipping", clipping},
      {"annotations", {{{"position", {2.6, 2.6, 0.5}}, {"title", "sphere"}}}}};
  nestlight::test::writeFile(dir.file("state.json"), state.dump());
  nestlight::test::writeFile(dir.file("c/scene.json"), scene.dump());
  const std::string size = " --width 96 --height 72";
  std::string out;
  ASSERT_EQ(runCli("render " + dir.file("c/scene.json") + size + " --state " +
                       dir.file("state.json") + " -o " + dir.file("state.exr"),
                   &out),
            0)
      << out;
  nlohmann::json edited = scene;
  edited["camera"]["eye"] = state["camera"]["eye"];
  edited["camera"]["target"] = state["camera"]["target"];
  edited["camera"]["fov"] = 60;
  edited["gi"]["method"] = "raster";
  edited["gi"]["parameters"] = {{"splat_scale", 1.5}};
  edited["octrees"][0]["clipping"] = clipping;
  nestlight::test::writeFile(dir.file("c/edited.json"), edited.dump());
  ASSERT_EQ(
      runCli("render " + dir.file("c/edited.json") + size + " -o " + dir.file("edited.exr"), &out),
      0)
      << out;
  const auto a = nestlight::gi::readHdrImage(dir.file("state.exr")),
             b = nestlight::gi::readHdrImage(dir.file("edited.exr"));
  EXPECT_LT(meanAbsDifference(a, b), 1e-6) << "the state and the fields it stands for differ";
  // Without the state's splat scale (its parameters are the method's) the image changes.
  edited["gi"]["parameters"] = nlohmann::json::object();
  nestlight::test::writeFile(dir.file("c/plain.json"), edited.dump());
  ASSERT_EQ(
      runCli("render " + dir.file("c/plain.json") + size + " -o " + dir.file("plain.exr"), &out), 0)
      << out;
  EXPECT_GT(meanAbsDifference(nestlight::gi::readHdrImage(dir.file("plain.exr")), b), 1e-3);
  // The annotation is in the PNG, not in the EXR (the method's radiance).
  const auto pa = nestlight::viewer::readImage(dir.file("state.png")),
             pb = nestlight::viewer::readImage(dir.file("edited.png"));
  size_t differing = 0;
  for (size_t i = 0; i < pa.rgba.size() && i < pb.rgba.size(); ++i)
    differing += std::abs(pa.rgba[i] - pb.rgba[i]) > 0.01f;
  EXPECT_GT(differing, 20u);
  // --clip adds its volumes to the scene's, as the state's do.
  nestlight::test::writeFile(dir.file("clip.json"), nlohmann::json{{"clipping", clipping}}.dump());
  edited["octrees"][0].erase("clipping");
  edited["gi"]["parameters"] = {{"splat_scale", 1.5}};
  nestlight::test::writeFile(dir.file("c/unclipped.json"), edited.dump());
  ASSERT_EQ(runCli("render " + dir.file("c/unclipped.json") + size + " --clip " +
                       dir.file("clip.json") + " -o " + dir.file("clip.exr"),
                   &out),
            0)
      << out;
  EXPECT_LT(meanAbsDifference(nestlight::gi::readHdrImage(dir.file("clip.exr")), b), 1e-6);
  // Another method given: the state's raster parameters are not its own and stay out.
  ASSERT_EQ(runCli("render " + dir.file("c/scene.json") + " --method reference --spp 1 --state " +
                       dir.file("state.json") + " -o " + dir.file("ref.exr"),
                   &out),
            0)
      << out;
}

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
