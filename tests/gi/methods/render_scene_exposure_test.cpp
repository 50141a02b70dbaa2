// The exposure of `render scene.json`'s PNG (docs/SCENE.md, "PNG exposure"): automatic unless the
// command line or the scene file gives one, and never applied to the EXR, whose pixels must be
// bit for bit those of a render that writes no PNG at all.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>
#include <string>

#include "gi/floor_scene.h"
#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/render_scene.h"
#include "nestlight/gi/tone_map.h"
#include "test_support.h"

namespace nestlight::gi {
namespace {

using json = nlohmann::json;

// The floor (albedo 0.5) under a sun of irradiance 20 straight down: radiance 0.5 * 20 / pi = 3.18
// everywhere in view, white at 0 EV. Direct light only, which has no noise under a sun.
std::filesystem::path sunlitFloor(const test::TempDir& t, const std::string& name, bool png,
                                  std::optional<double> fileExposure) {
  json j = floorSceneJson(t, 24);
  j["materials"] = {{"floor", {{"type", "lambert"}, {"base_color", 0.5}}}};
  j["lights"] = json::array(
      {json{{"type", "directional"}, {"direction", {0.0, 0.0, -1.0}}, {"irradiance", 20.0}}});
  j["gi"] = {{"method", "direct"}, {"mode", "albedo"}, {"samples_per_pixel", 2}};
  j["output"] = {{"exr", name + ".exr"}};
  if (png) j["output"]["png"] = name + ".png";
  if (fileExposure) j["output"]["exposure"] = *fileExposure;
  const auto file = t.path() / (name + ".json");
  std::ofstream(file) << j.dump(2);
  return file;
}

bool samePixels(const HdrImage& a, const HdrImage& b) {
  return a.width == b.width && a.height == b.height &&
         std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)) == 0;
}

// The PNG's mean display value (all pixels show the floor).
double meanPng(const std::filesystem::path& file) {
  const HdrImage png = readPng(file.string());
  double sum = 0;
  for (float v : png.rgb) sum += v;
  return sum / double(png.rgb.size());
}

TEST(RenderSceneExposure, PngExposedExrLinearAndUnscaled) {
  test::TempDir t;
  SceneRenderOverrides quiet;
  quiet.quiet = true;
  const SceneRenderReport plain = renderSceneFile(sunlitFloor(t, "plain", false, {}), quiet);
  EXPECT_FALSE(plain.pngExposure.has_value());
  const HdrImage unscaled = readHdrImage((t.path() / "plain.exr").string());
  const double radiance = 0.5 * 20 / M_PI;
  ASSERT_NEAR(unscaled.get(12, 12).g, radiance, 1e-3 * radiance);

  // Automatic: the floor (every pixel, so its 99th percentile) lands at 0.8, below white.
  const SceneRenderReport a = renderSceneFile(sunlitFloor(t, "auto", true, {}), quiet);
  ASSERT_TRUE(a.pngExposure.has_value());
  EXPECT_NEAR(*a.pngExposure, std::log2(0.8 / radiance), 1e-3);
  EXPECT_NEAR(meanPng(t.path() / "auto.png"), srgbEncode(0.8f), 1.0 / 255);
  EXPECT_TRUE(samePixels(readHdrImage((t.path() / "auto.exr").string()), unscaled));

  // The scene file's exposure wins over the automatic one: 3.18 / 8 = 0.40, sRGB 0.66.
  const SceneRenderReport f = renderSceneFile(sunlitFloor(t, "file", true, -3.0), quiet);
  EXPECT_EQ(f.pngExposure, -3.0);
  EXPECT_NEAR(meanPng(t.path() / "file.png"), srgbEncode(float(radiance / 8)), 1.0 / 255);
  EXPECT_TRUE(samePixels(readHdrImage((t.path() / "file.exr").string()), unscaled));

  // The command line wins over both: +3 EV is white; the EXR (here given with -o, the PNG beside
  // it) is still the unscaled render.
  SceneRenderOverrides cli = quiet;
  cli.exposure = 3.0;
  cli.output = t.path() / "cli.exr";
  const SceneRenderReport c = renderSceneFile(sunlitFloor(t, "cli-scene", true, -3.0), cli);
  EXPECT_EQ(c.pngExposure, 3.0);
  EXPECT_EQ(meanPng(t.path() / "cli.png"), 1.0);
  EXPECT_TRUE(samePixels(readHdrImage((t.path() / "cli.exr").string()), unscaled));
}

}  // namespace
}  // namespace nestlight::gi
