// The windowed viewer under a virtual X server: opens a scan, turns the camera for a number of
// frames and saves a screenshot; the screenshot must show the scan.
#include <cmath>
#include <cstdlib>
#include <fstream>

#include "nestlight/converters/builder.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/viewer/image.h"
#include "test_support.h"

using namespace nestlight;
namespace fs = std::filesystem;

namespace {
// A synthetic scan converted into `tmp`/s.octree.
fs::path syntheticOctree(const test::TempDir& tmp, uint64_t points) {
  SyntheticSpec spec;
  spec.points = points;
  std::vector<std::unique_ptr<PointReader>> r;
  r.push_back(openSynthetic(spec));
  BuildOptions o;
  o.output = tmp.path() / "s.octree";
  o.progress = ProgressMode::Quiet;
  buildOctree(std::move(r), o);
  return o.output;
}

// xvfb-run with the panel's state file under `tmp` (XDG_CONFIG_HOME), never in the real home.
std::string xvfbIn(const test::TempDir& tmp) {
  return "XDG_CONFIG_HOME=" + tmp.file("config") + " xvfb-run -a -s '-screen 0 640x480x24' ";
}
}  // namespace

TEST(Window, XvfbOpensMovesAndTakesScreenshot) {
  if (std::system("command -v xvfb-run >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "xvfb-run is not installed";
  test::TempDir tmp;
  const fs::path octree = syntheticOctree(tmp, 200'000);
  const std::string shot = tmp.file("shot.png");
  std::string out;
  const std::string cmd = xvfbIn(tmp) + ::nestlight::test::nestlightBinary() + " view " +
                          octree.string() +
                          " --width 320 --height 240 --frames 40 --orbit 3 --screenshot " + shot;
  const int rc = std::system((cmd + " > " + tmp.file("log.txt") + " 2>&1").c_str());
  out = test::readFile(tmp.file("log.txt"));
  ASSERT_EQ(rc, 0) << out;
  ASSERT_TRUE(fs::exists(shot)) << out;
  viewer::Image img = viewer::readImage(shot);
  EXPECT_EQ(img.width, 320);
  EXPECT_EQ(img.height, 240);
  // The scan covers a good part of the picture: pixels that are neither the background colour
  // (0.08, 0.08, 0.10) nor black (an empty or failed frame).
  size_t covered = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const float* p = img.at(x, y);
      const float offBackground =
          std::fabs(p[0] - 0.08f) + std::fabs(p[1] - 0.08f) + std::fabs(p[2] - 0.10f);
      if (offBackground > 0.05f && p[0] + p[1] + p[2] > 0.05f) ++covered;
    }
  EXPECT_GT(double(covered) / (320.0 * 240.0), 0.1) << out;
  EXPECT_NE(out.find("GLFW window"), std::string::npos) << out;
}

TEST(Window, ViewsASceneFileWithItsCameraAndDisplaySettings) {
  if (std::system("command -v xvfb-run >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "xvfb-run is not installed";
  test::TempDir tmp;
  syntheticOctree(tmp, 100'000);
  {
    std::ofstream f(tmp.file("scene.json"));
    f << R"({"octrees": ["s.octree"], "camera": {"eye": [150, -60, 80], "target": [50, 50, 10], "fov": 50},
             "display": {"splatting": "basic", "edl_strength": 0}})";
  }
  const std::string shot = tmp.file("shot.png");
  const std::string xvfb = xvfbIn(tmp);
  const std::string cmd =
      xvfb + ::nestlight::test::nestlightBinary() + " view " + tmp.file("scene.json") +
      " --show points --width 160 --height 120 --frames 20 --screenshot " + shot;
  const int rc = std::system((cmd + " > " + tmp.file("log.txt") + " 2>&1").c_str());
  const std::string out = test::readFile(tmp.file("log.txt"));
  ASSERT_EQ(rc, 0) << out;
  viewer::Image img = viewer::readImage(shot);
  size_t covered = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const float* p = img.at(x, y);
      covered +=
          std::fabs(p[0] - 0.08f) + std::fabs(p[1] - 0.08f) + std::fabs(p[2] - 0.10f) > 0.05f;
    }
  EXPECT_GT(double(covered) / (160.0 * 120.0), 0.1) << out;
  // The scene's camera is the one used: looking away from the scan, the frame is empty (the
  // default camera, which frames the scan, would fill it).
  {
    std::ofstream f(tmp.file("away.json"));
    f << R"({"octrees": ["s.octree"], "camera": {"eye": [150, -60, 80], "target": [250, -160, 150]}})";
  }
  const std::string away = tmp.file("away.png");
  ASSERT_EQ(
      std::system((xvfb + ::nestlight::test::nestlightBinary() + " view " + tmp.file("away.json") +
                   " --show points --width 160 --height 120 --frames 5 --screenshot " + away +
                   " > " + tmp.file("away.txt") + " 2>&1")
                      .c_str()),
      0)
      << test::readFile(tmp.file("away.txt"));
  viewer::Image empty = viewer::readImage(away);
  size_t seen = 0;
  for (int y = 0; y < empty.height; ++y)
    for (int x = 0; x < empty.width; ++x) {
      const float* p = empty.at(x, y);
      seen += std::fabs(p[0] - 0.08f) + std::fabs(p[1] - 0.08f) + std::fabs(p[2] - 0.10f) > 0.05f;
    }
  EXPECT_EQ(seen, 0u);
  // By default a scene opens on its GI method (the path tracer here, the default of a scene that
  // names none, accumulating progressively up to --spp): the scan's recorded colour as radiance
  // on a black background (no environment), and the method line in the log.
  const std::string gi = tmp.file("gi.png");
  ASSERT_EQ(
      std::system((xvfb + ::nestlight::test::nestlightBinary() + " view " + tmp.file("scene.json") +
                   " --spp 16 --width 160 --height 120 --frames 20 --screenshot " + gi + " > " +
                   tmp.file("gi.txt") + " 2>&1")
                      .c_str()),
      0)
      << test::readFile(tmp.file("gi.txt"));
  EXPECT_NE(test::readFile(tmp.file("gi.txt")).find("reference progressively, up to 16 samples"),
            std::string::npos)
      << test::readFile(tmp.file("gi.txt"));
  viewer::Image lit = viewer::readImage(gi);
  size_t nonBlack = 0;
  for (int y = 0; y < lit.height; ++y)
    for (int x = 0; x < lit.width; ++x)
      nonBlack += lit.at(x, y)[0] + lit.at(x, y)[1] + lit.at(x, y)[2] > 0.02f;
  EXPECT_GT(double(nonBlack) / (160.0 * 120.0), 0.1);
  // A scene that names an unknown splatting stops with the file and the field.
  {
    std::ofstream f(tmp.file("bad.json"));
    f << R"({"octrees": ["s.octree"], "display": {"splatting": "soft"}})";
  }
  const int bad = std::system((::nestlight::test::nestlightBinary() + " view " +
                               tmp.file("bad.json") + " > " + tmp.file("bad.txt") + " 2>&1")
                                  .c_str());
  EXPECT_NE(bad, 0);
  EXPECT_NE(test::readFile(tmp.file("bad.txt")).find("scene.display.splatting"), std::string::npos)
      << test::readFile(tmp.file("bad.txt"));
}

// A scene of meshes alone (no scan): the viewer opens on its GI method, framed by the meshes when
// the scene has no camera, and refuses the point view by name.
TEST(Window, ViewsASceneOfMeshesAlone) {
  if (std::system("command -v xvfb-run >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "xvfb-run is not installed";
  test::TempDir tmp;
  {
    // A unit cube, 8 vertices and 12 triangles, far from the origin as a survey would place it.
    std::ofstream f(tmp.file("cube.obj"));
    for (int i = 0; i < 8; ++i)
      f << "v " << 1000 + (i & 1) << " " << 2000 + ((i >> 1) & 1) << " " << ((i >> 2) & 1) << "\n";
    f << "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
  }
  {
    std::ofstream f(tmp.file("meshes.json"));
    f << R"({"meshes": [{"path": "cube.obj"}],
             "lights": [{"type": "directional", "direction": [-0.3, -0.5, -1], "irradiance": 3}],
             "gi": {"method": "raster"}})";
  }
  const std::string view =
      ::nestlight::test::nestlightBinary() + " view " + tmp.file("meshes.json");
  const std::string shot = tmp.file("shot.png");
  const int rc =
      std::system((xvfbIn(tmp) + view + " --width 160 --height 120 --frames 5 --screenshot " +
                   shot + " > " + tmp.file("log.txt") + " 2>&1")
                      .c_str());
  const std::string out = test::readFile(tmp.file("log.txt"));
  ASSERT_EQ(rc, 0) << out;
  viewer::Image img = viewer::readImage(shot);
  // The cube, lit by the sun, covers part of the frame; the background (no environment) is black.
  size_t lit = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      lit += img.at(x, y)[0] + img.at(x, y)[1] + img.at(x, y)[2] > 0.05f;
  EXPECT_GT(double(lit) / (160.0 * 120.0), 0.05) << out;
  EXPECT_LT(double(lit) / (160.0 * 120.0), 0.95) << out;
  const int points =
      std::system((view + " --show points > " + tmp.file("points.txt") + " 2>&1").c_str());
  EXPECT_NE(points, 0);
  EXPECT_NE(test::readFile(tmp.file("points.txt")).find("no scan to show as points"),
            std::string::npos)
      << test::readFile(tmp.file("points.txt"));
}
