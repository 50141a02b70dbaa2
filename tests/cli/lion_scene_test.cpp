// The bunny and the gargoyle from ../shared/data inserted into the lion scan (examples/lion),
// rendered in both modes by the reference (issue 4). Skips when the data is absent.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "nestlight/gi/hdr_image.h"
#include "test_support.h"

using namespace nestlight;
namespace fs = std::filesystem;

TEST(LionScene, BunnyAndGargoyleRenderInBothModes) {
  NL_REQUIRE_SHARED("scans/lion_takanawa_normals.ply");
  NL_REQUIRE_SHARED("meshes/bunny.ply");
  NL_REQUIRE_SHARED("meshes/gargoyle.ply");
  NL_REQUIRE_SHARED("hdr/royal_esplanade_1k.hdr");
  test::TempDir dir;
  std::string out;
  ASSERT_EQ(test::runCli(
                "convert --progress quiet " +
                    (::nestlight::test::sharedData() / "scans/lion_takanawa_normals.ply").string() +
                    " -o " + dir.file("lion.octree"),
                &out),
            0)
      << out;
  // The example scene, with its relative paths made absolute and the octree replaced.
  const fs::path example = ::nestlight::test::sourceDir() / "examples/lion/scene.json";
  auto scene = nlohmann::json::parse(test::readFile(example.string()));
  scene["octrees"][0]["path"] = dir.file("lion.octree");
  for (auto& m : scene["meshes"])
    m["path"] = fs::weakly_canonical(example.parent_path() / m["path"].get<std::string>()).string();
  scene["environment"]["path"] =
      fs::weakly_canonical(example.parent_path() / scene["environment"]["path"].get<std::string>())
          .string();
  scene.erase("output");
  // The same view without the objects, to find the pixels they cover.
  auto bare = scene;
  bare.erase("meshes");
  test::writeFile(dir.file("scene.json"), scene.dump());
  test::writeFile(dir.file("bare.json"), bare.dump());
  for (const char* mode : {"radiance_cache", "albedo"}) {
    const std::string a = dir.file(std::string("with_") + mode + ".exr"),
                      b = dir.file(std::string("bare_") + mode + ".exr");
    const std::string common = std::string(" --spp 4 --width 64 --height 48 --mode ") + mode;
    ASSERT_EQ(test::runCli("render " + dir.file("scene.json") + common + " -o " + a, &out), 0)
        << out;
    EXPECT_NE(out.find("bunny.ply: 69451 triangles"), std::string::npos) << out;
    EXPECT_NE(out.find("gargoyle.ply: 50000 triangles"), std::string::npos) << out;
    ASSERT_EQ(test::runCli("render " + dir.file("bare.json") + common + " -o " + b, &out), 0)
        << out;
    gi::HdrImage with = gi::readHdrImage(a), without = gi::readHdrImage(b);
    int changed = 0;
    for (size_t i = 0; i < with.pixels(); ++i) {
      ASSERT_TRUE(std::isfinite(with.rgb[3 * i]));
      float d = std::abs(with.rgb[3 * i] - without.rgb[3 * i]) +
                std::abs(with.rgb[3 * i + 1] - without.rgb[3 * i + 1]);
      changed += d > 0.05f;
    }
    // The two objects on the plinth's front cover about 1.2% of the frame (944 of 76 800 pixels
    // at 320 x 240: ~38 of 3072 here) and their shadows add some; noise of 4 spp alone changes a
    // pixel by more than 0.05 rarely, so 25 pixels is a safe floor (measured: 43).
    EXPECT_GT(changed, 25) << mode;
  }
}
