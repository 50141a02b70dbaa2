// `nestlight view`'s command line for scene files: the method, its variant and its parameters as
// `render` takes them, checked before a window opens (--dry-run prints what the window would open
// with, so these run without a display).
#include <gtest/gtest.h>

#include "test_support.h"

namespace {

std::string cornellScene(const nestlight::test::TempDir& dir) {
  std::string out;
  EXPECT_EQ(
      nestlight::test::runCli(
          "make-scene cornell -q -n 20k --width 24 --height 16 -o " + dir.file("cornell"), &out),
      0)
      << out;
  return dir.file("cornell/scene.json");
}

}  // namespace

TEST(ViewOptions, MethodVariantAndParametersParseAsRenderTakesThem) {
  nestlight::test::TempDir dir;
  const std::string scene = cornellScene(dir);
  std::string out;
  // The refusal: "--method pbgi: arguments were not expected".
  ASSERT_EQ(nestlight::test::runCli(
                "view " + scene + " --method pbgi --variant classic --bounces 2 --dry-run", &out),
            0)
      << out;
  EXPECT_NE(out.find("method pbgi"), std::string::npos) << out;
  EXPECT_NE(out.find("2 bounces"), std::string::npos) << out;
  EXPECT_NE(out.find("\"variant\":\"classic\""), std::string::npos) << out;
  // The scene names the path tracer: without --method it is the one the window opens with.
  ASSERT_EQ(nestlight::test::runCli("view " + scene + " --spp 8 --dry-run", &out), 0) << out;
  EXPECT_NE(out.find("method reference"), std::string::npos) << out;
  EXPECT_NE(out.find("8 samples per pixel"), std::string::npos) << out;
  // --param goes through the method's declaration, as `render`'s does.
  ASSERT_EQ(
      nestlight::test::runCli(
          "view " + scene + " --method vpl --param vpls=64 --param clamp=0.5 --dry-run", &out),
      0)
      << out;
  EXPECT_NE(out.find("\"vpls\":64"), std::string::npos) << out;
  EXPECT_NE(out.find("\"clamp\":0.5"), std::string::npos) << out;
}

TEST(ViewOptions, BadMethodOptionsStopBeforeAWindow) {
  nestlight::test::TempDir dir;
  const std::string scene = cornellScene(dir);
  std::string out;
  EXPECT_NE(
      nestlight::test::runCli("view " + scene + " --method pbgi --variant bogus --dry-run", &out),
      0);
  EXPECT_NE(out.find("bogus"), std::string::npos) << out;
  EXPECT_NE(nestlight::test::runCli("view " + scene + " --method nope --dry-run", &out), 0);
  EXPECT_NE(out.find("nope"), std::string::npos) << out;
  // A value out of the declared range names the field, as in a scene file.
  EXPECT_NE(nestlight::test::runCli(
                "view " + scene + " --method pbgi --param micro_buffer=3 --dry-run", &out),
            0);
  EXPECT_NE(out.find("scene.gi.parameters.micro_buffer"), std::string::npos) << out;
  // A typo is not ignored.
  EXPECT_NE(nestlight::test::runCli("view " + scene +
                                        " --method raster --param shadow_map=64 "
                                        "--dry-run",
                                    &out),
            0);
  EXPECT_NE(out.find("shadow_map"), std::string::npos) << out;
  // An octree has no GI method to set.
  EXPECT_NE(nestlight::test::runCli(
                "view " + dir.file("cornell/scan.octree") + " --method pbgi --dry-run", &out),
            0);
  EXPECT_NE(out.find("applies to scene files"), std::string::npos) << out;
}
