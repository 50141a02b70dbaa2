// The window with every registered GI method (issue 30), under a virtual X server: each chosen
// with --method on a small Cornell room, its screenshot lit and unlike the point view's; the path
// tracer's progressive view converging as it accumulates; the panel's state kept in the config
// folder the test names, never the real home.
#include <cmath>
#include <cstdlib>
#include <fstream>

#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/metrics.h"
#include "nestlight/viewer/image.h"
#include "test_support.h"

namespace fs = std::filesystem;

namespace {

bool haveXvfb() {
  return std::system("command -v xvfb-run >/dev/null 2>&1") == 0;
}

// A 20k-point Cornell room: every method builds and renders it in a few seconds on llvmpipe.
std::string smallCornell(const nestlight::test::TempDir& tmp) {
  std::string out;
  EXPECT_EQ(
      nestlight::test::runCli(
          "make-scene cornell -q -n 20k --width 96 --height 72 -o " + tmp.file("cornell"), &out),
      0)
      << out;
  return tmp.file("cornell/scene.json");
}

// `nestlight view ARGS` in a 96 x 72 window under xvfb-run, the panel's state under tmp/config;
// the exit code, with the log in `log`.
int runView(const nestlight::test::TempDir& tmp, const std::string& args, std::string* log) {
  const std::string logFile = tmp.file("view-log.txt");
  const std::string cmd = "XDG_CONFIG_HOME=" + tmp.file("config") +
                          " xvfb-run -a -s '-screen 0 640x480x24' " +
                          nestlight::test::nestlightBinary() + " view " + args +
                          " --width 96 --height 72 > " + logFile + " 2>&1";
  const int rc = std::system(cmd.c_str());
  *log = nestlight::test::readFile(logFile);
  return rc;
}

// Pixels brighter than a dark grey: the room's walls are lit in every method's image.
double litFraction(const nestlight::viewer::Image& img) {
  size_t lit = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const float* p = img.at(x, y);
      lit += p[0] + p[1] + p[2] > 0.15f;
    }
  return double(lit) / (double(img.width) * img.height);
}

double meanAbsoluteDifference(const nestlight::viewer::Image& a,
                              const nestlight::viewer::Image& b) {
  double sum = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x)
      for (int c = 0; c < 3; ++c) sum += std::fabs(a.at(x, y)[c] - b.at(x, y)[c]);
  return sum / (3.0 * a.width * a.height);
}

}  // namespace

TEST(WindowMethods, EveryRegisteredMethodIsChosenWithMethodAndShown) {
  if (!haveXvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  nestlight::test::noLeakChecksInGlChildren();
  nestlight::test::TempDir tmp;
  const std::string scene = smallCornell(tmp);
  std::string log;
  const std::string pointsShot = tmp.file("points.png");
  ASSERT_EQ(runView(tmp, scene + " --show points --frames 10 --screenshot " + pointsShot, &log), 0)
      << log;
  const nestlight::viewer::Image points = nestlight::viewer::readImage(pointsShot);
  for (const std::string& method : nestlight::gi::registeredMethodNames()) {
    SCOPED_TRACE(method);
    const nestlight::gi::MethodInfo& info = *nestlight::gi::findMethod(method);
    const std::string shot = tmp.file(method + ".png");
    // pbgi at its smallest micro-buffers, so that it stays a few seconds on llvmpipe.
    const std::string extra = method == "pbgi" ? " --variant classic --param micro_buffer=4" : "";
    ASSERT_EQ(
        runView(tmp,
                scene + " --method " + method + extra + " --spp 8 --frames 3 --screenshot " + shot,
                &log),
        0)
        << log;
    // The log says how the method is shown: in real time, or progressively.
    EXPECT_NE(log.find("view: " + method +
                       (info.gpu ? " through the GI frame" : " progressively, up to 8 samples")),
              std::string::npos)
        << log;
    const nestlight::viewer::Image img = nestlight::viewer::readImage(shot);
    ASSERT_EQ(img.width, 96);
    ASSERT_EQ(img.height, 72);
    // Lit: the room fills the frame (its walls well above black in every method, at 8 samples
    // per pixel too); a black or failed frame has no such pixels.
    EXPECT_GT(litFraction(img), 0.5) << log;
    // The method's image, not the point view's: the points show the recorded colours with
    // eye-dome lighting on the viewer's grey background, the methods light the room; a mean
    // difference of 2% of the range is far above what two renders of one image differ by.
    EXPECT_GT(meanAbsoluteDifference(img, points), 0.02) << log;
  }
}

// The path tracer's progressive view: the more samples it has accumulated when the screenshot is
// taken, the nearer its image is to a converged render of the same view (the error of a mean of n
// samples falls as 1 / sqrt(n): 16 times the samples, a quarter of the error).
TEST(WindowMethods, ProgressiveReferenceConvergesAsItAccumulates) {
  if (!haveXvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  nestlight::test::noLeakChecksInGlChildren();
  nestlight::test::TempDir tmp;
  const std::string scene = smallCornell(tmp);
  std::string out;
  ASSERT_EQ(nestlight::test::runCli("render " + scene +
                                        " --spp 512 --width 96 --height 72 "
                                        "-o " +
                                        tmp.file("truth.exr"),
                                    &out),
            0)
      << out;
  const nestlight::gi::HdrImage truth = nestlight::gi::readHdrImage(tmp.file("truth.exr"));
  double error[2] = {0, 0};
  const int spp[2] = {2, 32};
  for (int i = 0; i < 2; ++i) {
    const std::string shot = tmp.file("progressive" + std::to_string(spp[i]) + ".exr");
    std::string log;
    ASSERT_EQ(
        runView(tmp,
                scene + " --spp " + std::to_string(spp[i]) + " --frames 4 --screenshot " + shot,
                &log),
        0)
        << log;
    EXPECT_NE(log.find("reference " + std::to_string(spp[i]) + " samples per pixel"),
              std::string::npos)
        << log;
    nestlight::gi::ImageAttributes attrs;
    const nestlight::gi::HdrImage img = nestlight::gi::readHdrImage(shot, &attrs);
    ASSERT_EQ(img.width, truth.width);
    ASSERT_EQ(img.height, truth.height);
    EXPECT_EQ(attrs["nestlight:samples"], std::to_string(spp[i]));
    error[i] = nestlight::gi::relativeL2(img, truth);
  }
  // Expected ratio 4 (less the truth's own noise, 1/16 of the 32-sample image's variance); 0.5
  // leaves room for the camera's round trip through the orbit controller (sub-pixel).
  EXPECT_LT(error[1], 0.5 * error[0]) << error[0] << " " << error[1];
  EXPECT_GT(error[0], 0);
}

// The panel's state (position, size, collapsed) is Dear ImGui's ini file under $XDG_CONFIG_HOME:
// a panel collapsed in one run stays collapsed in the next, and the file is where the test said.
TEST(WindowMethods, PanelStateIsKeptInTheConfigFolder) {
  if (!haveXvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  nestlight::test::noLeakChecksInGlChildren();
  nestlight::test::TempDir tmp;
  const std::string scene = smallCornell(tmp);
  const fs::path ini = tmp.path() / "config" / "nestlight" / "imgui.ini";
  fs::create_directories(ini.parent_path());
  nestlight::test::writeFile(ini.string(),
                             "[Window][nestlight]\nPos=30,20\nSize=300,200\nCollapsed=1\n");
  std::string log;
  ASSERT_EQ(runView(tmp, scene + " --method raster --frames 3", &log), 0) << log;
  const std::string kept = nestlight::test::readFile(ini.string());
  EXPECT_NE(kept.find("[Window][nestlight]\nPos=30,20\nSize=300,200\nCollapsed=1"),
            std::string::npos)
      << kept;
}
