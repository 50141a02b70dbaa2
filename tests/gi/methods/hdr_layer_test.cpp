// A scene's octrees[].colour: every GI method lights with the colour source it names. The HDR
// colour layer of an emitting sphere of scan points is its recorded colour (linear) times k = 40,
// far beyond what 8 or 16 bits record; light is linear in the emitters, so every method's image
// with "colour": "hdr" must be k times its image with "rgb", pixel for pixel. Tolerance 1%: RGB9E5
// (what the GPU point format carries the layer in) rounds to half a step of 2^-9 of the largest
// channel (here all three are equal: 0.1%), and the layer's half floats add 2^-11; the methods'
// sampling (same seeds, same sample placement: importance is scaled by k everywhere) cancels.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "gi/sphere_scan.h"
#include "nestlight/gi/method.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/scene.h"
#include "nestlight/gi/srgb.h"
#include "test_support.h"

namespace nestlight::gi {
namespace {

class HdrLayerEveryMethod : public ::testing::TestWithParam<std::string> {};

TEST_P(HdrLayerEveryMethod, LightsAsTheLayerSays) {
  nestlight::test::TempDir t;
  buildSphereScan(t, 40000, 2.0f, 150);
  const float k = 40.0f, L = k * srgbDecode(150.0f / 255.0f);
  nestlight::test::writeColourLayer(t.path() / "sphere.octree", "hdr", [&](const NodeKey&, size_t) {
    return std::array<float, 3>{L, L, L};
  });
  const MethodInfo* info = findMethod(GetParam());
  ASSERT_NE(info, nullptr);
  Scene s = boxInSphereScene(t, 0.5, info->name, nlohmann::json::object());
  info->applyQuality(s.gi,
                     info->qualityName == "samples per pixel" ? 4 : info->defaultQualities.front());
  // Wide enough that the sphere shows around the box: the raster method (direct light only, and
  // none here) draws nothing but the scan's own emission.
  s.camera.fovYDegrees = 100;
  const HdrImage recorded = createMethod(s, {true, false})->render(s.camera).image;
  s.octrees[0].colour = "hdr";
  const HdrImage hdr = createMethod(s, {true, false})->render(s.camera).image;
  double worst = 0, sumRecorded = 0, sumHdr = 0;
  size_t lit = 0;
  for (size_t i = 0; i < recorded.rgb.size(); ++i) {
    sumRecorded += recorded.rgb[i], sumHdr += hdr.rgb[i];
    if (recorded.rgb[i] < 1e-3f) continue;
    ++lit;
    worst = std::max(worst, std::abs(hdr.rgb[i] / (k * recorded.rgb[i]) - 1.0));
  }
  std::printf(
      "%s: hdr / rgb = %.5f over the image (k = %.0f), worst pixel off by %.4f, %zu lit values\n",
      info->name.c_str(), sumHdr / sumRecorded, k, worst, lit);
  EXPECT_GT(lit, recorded.rgb.size() / 2) << info->name;
  EXPECT_NEAR(sumHdr / sumRecorded / k, 1.0, 0.01) << info->name;
  EXPECT_LT(worst, 0.01) << info->name;
}

INSTANTIATE_TEST_SUITE_P(Registered, HdrLayerEveryMethod,
                         ::testing::ValuesIn(registeredMethodNames()),
                         [](const auto& info) { return info.param; });

// A colour source the octree lacks fails when the scene is read, naming the field.
TEST(HdrLayer, AMissingLayerIsNamedWithItsField) {
  nestlight::test::TempDir t;
  buildSphereScan(t, 2000, 2.0f, 150);
  Scene s = boxInSphereScene(t, 0.5, "raster", nlohmann::json::object());
  nlohmann::json j = nlohmann::json::parse(nestlight::test::readFile(t.file("scene.json")));
  j["octrees"][0]["colour"] = "hdr";
  nestlight::test::writeFile(t.file("scene.json"), j.dump());
  const Error e = nestlight::test::errorOf([&] { loadScene(t.file("scene.json")); });
  EXPECT_NE(std::string(e.what()).find("octrees[0].colour"), std::string::npos) << e.what();
  EXPECT_NE(std::string(e.what()).find("no colour layer 'hdr'"), std::string::npos) << e.what();
  j["octrees"][0]["colour"] = 3;
  nestlight::test::writeFile(t.file("scene.json"), j.dump());
  const Error e2 = nestlight::test::errorOf([&] { loadScene(t.file("scene.json")); });
  EXPECT_NE(std::string(e2.what()).find("octrees[0].colour"), std::string::npos) << e2.what();
}

}  // namespace
}  // namespace nestlight::gi
