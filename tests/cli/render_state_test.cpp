// `render --state`, `--clip` and `--pick` from the command line: a view state renders the image its
// fields describe (the same bytes as the options they stand for), options given win over it,
// its annotations are drawn, a state from elsewhere warns, a bad one names the field, and a pick
// prints the point in the scan's coordinates.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "nestlight/viewer/image.h"
#include "test_support.h"

namespace render_state_test {

using nestlight::test::runCli;
using nestlight::test::TempDir;

// A small generated building in national-grid coordinates, converted.
std::string makeOctree(const TempDir& dir) {
  return nestlight::test::generatedOctree(dir, "30k", 20, "512000,5412000,300");
}

const char* kSmall = " --width 96 --height 64 --wait-complete";

TEST(RenderState, StateRendersWhatItsFieldsSay) {
  nestlight::test::noLeakChecksInGlChildren();  // the renders run GL (llvmpipe)
  TempDir dir;
  const std::string oct = makeOctree(dir);
  nlohmann::json state = {{"version", 1},
                          {"camera",
                           {{"eye", {512030.0, 5411975.0, 325.0}},
                            {"target", {512010.0, 5412010.0, 305.0}},
                            {"fov", 50}}},
                          {"colour", {{"mode", "elevation"}}},
                          {"splatting", {{"splatting", "basic"}, {"edl", 0.5}}},
                          {"clipping",
                           {{{"type", "box"},
                             {"center", {512010.0, 5412010.0, 305.0}},
                             {"size", {12.0, 12.0, 40.0}},
                             {"rotation", {0, 0, 20}}}}}};
  nestlight::test::writeFile(dir.file("view.json"), state.dump());
  nestlight::test::writeFile(dir.file("clip.json"),
                             nlohmann::json{{"clipping", state["clipping"]}}.dump());
  std::string out;
  ASSERT_EQ(runCli("render " + oct + kSmall + " --state " + dir.file("view.json") + " -o " +
                       dir.file("state.png"),
                   &out),
            0)
      << out;
  ASSERT_EQ(runCli("render " + oct + kSmall +
                       " --camera 512030,5411975,325,512010,5412010,305 --fov 50 --colour "
                       "elevation --splatting basic --edl 0.5 --clip " +
                       dir.file("clip.json") + " -o " + dir.file("options.png"),
                   &out),
            0)
      << out;
  EXPECT_EQ(nestlight::test::readFile(dir.file("state.png")),
            nestlight::test::readFile(dir.file("options.png")))
      << "the state and the options it stands for gave different images";
  // Without the clip the image shows more of the building.
  ASSERT_EQ(runCli("render " + oct + kSmall +
                       " --camera 512030,5411975,325,512010,5412010,305 --fov 50 --colour "
                       "elevation --splatting basic --edl 0.5 -o " +
                       dir.file("unclipped.png"),
                   &out),
            0)
      << out;
  EXPECT_NE(nestlight::test::readFile(dir.file("state.png")),
            nestlight::test::readFile(dir.file("unclipped.png")));
  // An option given wins over the state: --colour rgb is not the state's elevation.
  ASSERT_EQ(runCli("render " + oct + kSmall + " --state " + dir.file("view.json") +
                       " --splatting hqs -o " + dir.file("hqs.png"),
                   &out),
            0)
      << out;
  EXPECT_NE(nestlight::test::readFile(dir.file("state.png")),
            nestlight::test::readFile(dir.file("hqs.png")));
}

TEST(RenderState, AnnotationsAreDrawnAtTheirPoints) {
  nestlight::test::noLeakChecksInGlChildren();  // the renders run GL (llvmpipe)
  TempDir dir;
  const std::string oct = makeOctree(dir);
  nlohmann::json state = {
      {"camera", {{"eye", {512010.0, 5411960.0, 320.0}}, {"target", {512010.0, 5412010.0, 305.0}}}},
      {"annotations", {{{"position", {512010.0, 5412010.0, 305.0}}, {"title", "crack A"}}}}};
  nestlight::test::writeFile(dir.file("view.json"), state.dump());
  state.erase("annotations");
  nestlight::test::writeFile(dir.file("plain.json"), state.dump());
  std::string out;
  ASSERT_EQ(runCli("render " + oct + " --width 200 --height 120 --wait-complete --state " +
                       dir.file("view.json") + " -o " + dir.file("a.png"),
                   &out),
            0)
      << out;
  ASSERT_EQ(runCli("render " + oct + " --width 200 --height 120 --wait-complete --state " +
                       dir.file("plain.json") + " -o " + dir.file("b.png"),
                   &out),
            0)
      << out;
  const nestlight::frame::Image a = nestlight::viewer::readImage(dir.file("a.png")),
                                b = nestlight::viewer::readImage(dir.file("b.png"));
  // The target is the image's centre: the marker's ring passes 4 px from it, the title lies up
  // and to the right; far from both the images agree.
  size_t changedNear = 0, changedFar = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      const bool differs = std::abs(a.at(x, y)[0] - b.at(x, y)[0]) > 0.01f;
      const bool near = x >= 90 && x < 160 && y >= 40 && y < 70;
      (near ? changedNear : changedFar) += differs;
    }
  EXPECT_GT(changedNear, 50u);
  EXPECT_EQ(changedFar, 0u);
}

TEST(RenderState, StateFromElsewhereWarnsAndBadFieldsAreNamed) {
  nestlight::test::noLeakChecksInGlChildren();  // the renders run GL (llvmpipe)
  TempDir dir;
  const std::string oct = makeOctree(dir);
  nestlight::test::writeFile(dir.file("far.json"),
                             R"({"octree": {"bounds": [[0, 0, 0], [10, 10, 10]]},
          "camera": {"eye": [512030, 5411975, 325], "target": [512010, 5412010, 305]}})");
  std::string out;
  ASSERT_EQ(runCli("render " + oct + kSmall + " --state " + dir.file("far.json") + " -o " +
                       dir.file("far.png"),
                   &out),
            0)
      << out;
  EXPECT_NE(out.find("warning"), std::string::npos) << out;
  // A bad file: refused, naming what is wrong.
  auto refused = [&](const std::string& name, const std::string& option, const std::string& text,
                     const std::string& named) {
    nestlight::test::writeFile(dir.file(name + ".json"), text);
    EXPECT_EQ(runCli("render " + oct + kSmall + " " + option + " " + dir.file(name + ".json") +
                         " -o " + dir.file(name + ".png"),
                     &out),
              1);
    EXPECT_NE(out.find(named), std::string::npos) << out;
  };
  refused("bad", "--state", R"({"camera": {"eye": [1, "two", 3], "target": [0, 0, 0]}})",
          "camera.eye");
  refused("cross", "--clip",
          R"({"clipping": [{"type": "polygon", "points": [[0, 0], [1, 1], [1, 0], [0, 1]]}]})",
          "cross");
}

TEST(RenderPick, PrintsThePointInTheScansCoordinates) {
  nestlight::test::noLeakChecksInGlChildren();  // the renders run GL (llvmpipe)
  TempDir dir;
  const std::string oct = makeOctree(dir);
  std::string out;
  ASSERT_EQ(runCli("render " + oct + kSmall +
                       " --camera 512030,5411975,325,512010,5412010,305 --pick 48,32 --pick 0,0 "
                       "-o " +
                       dir.file("pick.png"),
                   &out),
            0)
      << out;
  // Six-digit eastings printed to the millimetre, not a shifted float frame.
  EXPECT_NE(out.find("pick 48,32: 5120"), std::string::npos) << out;
  EXPECT_NE(out.find(" 54120"), std::string::npos) << out;
  EXPECT_NE(out.find("pick 0,0: nothing"), std::string::npos) << out;
  EXPECT_NE(runCli("render " + oct + kSmall + " --pick 500,2 -o " + dir.file("p.png"), &out), 0);
  EXPECT_NE(out.find("outside"), std::string::npos) << out;
}

}  // namespace render_state_test
