// The viewer's heritage tools under a virtual X server, driven by scripted clicks: a distance
// measured on a national-grid scan snaps to the very points `render --pick` finds at the same
// pixels; an annotation and a clipping polygon are added; the view state saved (as Ctrl+S saves
// it) reloads into the same picture, which is compared with a golden and with `render --state`. A
// scene's view saves its GI method and parameters.
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <regex>

#include "golden.h"
#include "nestlight/viewer/image.h"
#include "test_support.h"

namespace window_tools_test {

namespace fs = std::filesystem;
using nestlight::test::runCli;
using nestlight::test::TempDir;

std::string xvfb(const TempDir& tmp) {
  return "XDG_CONFIG_HOME=" + tmp.file("config") + " xvfb-run -a -s '-screen 0 640x480x24' " +
         nestlight::test::nestlightBinary() + " ";
}

int run(const std::string& cmd, const TempDir& tmp, std::string* out) {
  const int rc = std::system((cmd + " > " + tmp.file("log.txt") + " 2>&1").c_str());
  *out = nestlight::test::readFile(tmp.file("log.txt"));
  return rc;
}

const char* kView = " --width 320 --height 240 --camera 512030,5411975,325,512010,5412010,303";

// Each test: a virtual X server (skipped without xvfb-run), a folder and a log.
class WindowTools : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::system("command -v xvfb-run >/dev/null 2>&1") != 0)
      GTEST_SKIP() << "xvfb-run is not installed";
  }
  // A small generated building in national-grid coordinates, converted.
  std::string building() {
    return nestlight::test::generatedOctree(tmp, "60k", 20, "512000,5412000,300");
  }
  TempDir tmp;
  std::string out;
};

TEST_F(WindowTools, MeasureAnnotateClipSaveAndReload) {
  const std::string oct = building();
  // 1. A distance between two clicks, saved at the end.
  ASSERT_EQ(run(xvfb(tmp) + "view " + oct + kView +
                    " --tool distance --click 140,150 --click 200,120 --frames 60 --save-state " +
                    tmp.file("s1.json"),
                tmp, &out),
            0)
      << out;
  const nlohmann::json s1 = nlohmann::json::parse(nestlight::test::readFile(tmp.file("s1.json")));
  ASSERT_EQ(s1["measurements"].size(), 1u) << s1.dump(1) << out;
  const nlohmann::json& m = s1["measurements"][0];
  EXPECT_EQ(m["type"], "distance");
  ASSERT_EQ(m["points"].size(), 2u);
  // The same pixels picked headless: the same points of the scan, to the last bit.
  ASSERT_EQ(runCli("render " + oct + kView + " --wait-complete --pick 140,150 --pick 200,120 -o " +
                       tmp.file("p.png"),
                   &out),
            0)
      << out;
  for (int i = 0; i < 2; ++i) {
    char want[128];
    std::snprintf(want, sizeof want, "%.3f %.3f %.3f", m["points"][i][0].get<double>(),
                  m["points"][i][1].get<double>(), m["points"][i][2].get<double>());
    EXPECT_NE(out.find(want), std::string::npos) << "vertex " << i << " " << want << "\n" << out;
  }
  // 2. An annotation and a clipping polygon (three clicks on the boxes) on top of
  // the saved state.
  ASSERT_EQ(
      run(xvfb(tmp) + "view " + oct + kView + " --state " + tmp.file("s1.json") +
              " --tool annotate --click 170,140 --frames 40 --save-state " + tmp.file("s2.json"),
          tmp, &out),
      0)
      << out;
  ASSERT_EQ(run(xvfb(tmp) + "view " + oct + kView + " --state " + tmp.file("s2.json") +
                    " --tool clip-polygon --click 120,145 --click 175,150 --click 170,118 "
                    "--frames 40 --save-state " +
                    tmp.file("s3.json"),
                tmp, &out),
            0)
      << out;
  const nlohmann::json s3 = nlohmann::json::parse(nestlight::test::readFile(tmp.file("s3.json")));
  EXPECT_EQ(s3["measurements"].size(), 1u) << s3.dump(1);
  EXPECT_EQ(s3["annotations"].size(), 1u) << s3.dump(1);
  ASSERT_EQ(s3["clipping"].size(), 1u) << s3.dump(1) << out;
  EXPECT_EQ(s3["clipping"][0]["type"], "polygon");
  EXPECT_EQ(s3["measurements"][0], s1["measurements"][0]) << "reloading moved the measurement";
  // 3. Reload: the window's screenshot (measurement, label and clipping drawn) against the golden,
  // and against the headless render of the same state.
  ASSERT_EQ(run(xvfb(tmp) + "view " + oct + " --width 320 --height 240 --state " +
                    tmp.file("s3.json") + " --frames 40 --screenshot " + tmp.file("shot.png"),
                tmp, &out),
            0)
      << out;
  nestlight::test::expectMatchesGolden(tmp.file("shot.png"), "viewer_tools", 3.f / 255, 0.01);
  ASSERT_EQ(runCli("render " + oct + " --width 320 --height 240 --wait-complete --state " +
                       tmp.file("s3.json") + " -o " + tmp.file("render.png"),
                   &out),
            0)
      << out;
  const auto a = nestlight::viewer::readImage(tmp.file("shot.png"));
  const auto b = nestlight::viewer::readImage(tmp.file("render.png"));
  // The window fits its near plane closer than the renderer (depth precision differs at splat
  // edges): a few pixels may differ, not the picture.
  EXPECT_LT(nestlight::viewer::compareImages(a, b, 3.f / 255).fraction, 0.03);
}

// The profile tool: two clicks cut a section of the resident cut, shown in its panel; every point
// of it lies in the section `nestlight profile` cuts from the whole octree along the same line.
TEST_F(WindowTools, ProfileOfTheResidentCutIsPartOfTheWholeSection) {
  const std::string oct = building();
  ASSERT_EQ(run(xvfb(tmp) + "view " + oct + kView +
                    " --tool profile --click 140,150 --click 200,120 --frames 40",
                tmp, &out),
            0)
      << out;
  auto numbersAfter = [&](const std::string& key) {
    const size_t at = out.find(key);
    EXPECT_NE(at, std::string::npos) << key << "\n" << out;
    double x = 0, y = 0;
    if (at != std::string::npos) std::sscanf(out.c_str() + at + key.size(), "%lf %lf", &x, &y);
    return std::array<double, 2>{x, y};
  };
  const auto a = numbersAfter("profile from "), b = numbersAfter("profile to ");
  size_t shown = 0;
  std::smatch match;
  ASSERT_TRUE(std::regex_search(out, match, std::regex(": ([0-9]+) points of the resident cut")))
      << out;
  shown = std::stoul(match[1]);
  EXPECT_GT(shown, 20u) << out;
  // The viewer's default width is 1% of the octree's cube (a few decimetres here): the CLI's
  // section along the same line, 1 m wide, from every level, holds at least as many points.
  char line[256];
  std::snprintf(line, sizeof line, "%.3f,%.3f,%.3f,%.3f", a[0], a[1], b[0], b[1]);
  ASSERT_EQ(
      runCli("profile " + oct + " --line " + line + " --width 1 -o " + tmp.file("s.las"), &out), 0)
      << out;
  size_t whole = 0;
  const size_t p = out.find("profile: ");
  ASSERT_NE(p, std::string::npos) << out;
  std::sscanf(out.c_str() + p + 9, "%zu", &whole);
  EXPECT_GE(whole, shown) << out;
}

// A scene's view saves the GI method and parameters the panel shows with its camera; the state
// reopens the scene with them.
TEST_F(WindowTools, SceneViewSavesItsMethodAndReloads) {
  ASSERT_EQ(runCli("make-scene cornell -q -n 20k --width 64 --height 48 -o " + tmp.file("c"), &out),
            0)
      << out;
  const std::string scene = tmp.file("c/scene.json");
  ASSERT_EQ(run(xvfb(tmp) + "view " + scene +
                    " --width 160 --height 120 --method raster --param splat_scale=1.5 "
                    "--frames 4 --save-state " +
                    tmp.file("s.json"),
                tmp, &out),
            0)
      << out;
  const nlohmann::json s = nlohmann::json::parse(nestlight::test::readFile(tmp.file("s.json")));
  EXPECT_EQ(s["gi"]["method"], "raster") << s.dump(1);
  EXPECT_EQ(s["gi"]["parameters"]["splat_scale"], 1.5) << s.dump(1);
  ASSERT_TRUE(s.contains("camera")) << s.dump(1);
  // The scene file says reference; the state's method and parameter win.
  ASSERT_EQ(runCli("view " + scene + " --state " + tmp.file("s.json") + " --dry-run", &out), 0)
      << out;
  EXPECT_NE(out.find("method raster"), std::string::npos) << out;
  EXPECT_NE(out.find("\"splat_scale\":1.5"), std::string::npos) << out;
}

}  // namespace window_tools_test
