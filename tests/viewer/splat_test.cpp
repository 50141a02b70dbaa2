// Splats sized from the data: no holes on an evenly sampled surface at any zoom, splat size
// pinned to the measured spacing (of the finest drawn node, whichever level a point belongs
// to), and the default camera framing the scan.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

#include "nestlight/converters/builder.h"
#include "nestlight/converters/reader.h"
#include "nestlight/frame/camera.h"
#include "nestlight/viewer/headless.h"
#include "nestlight/viewer/image.h"
#include "test_support.h"
#include "viewer/small_scan.h"

using namespace nestlight;
using namespace nestlight::viewer;
using namespace nestlight::frame;
namespace fs = std::filesystem;

namespace {

// A jittered grid on the plane z = 0 (a scanner's pattern): `n` x `n` points, `step` apart,
// each moved by up to 0.3 steps; colour varies smoothly. Written as XYZ text and converted.
fs::path gridPlane(const test::TempDir& tmp, const std::string& name, int n, double step,
                   uint32_t maxNodePoints) {
  const fs::path xyz = tmp.path() / (name + ".xyz");
  {
    std::ofstream f(xyz);
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> jitter(-0.3, 0.3);
    char line[128];
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const double px = (x + 0.5 + jitter(rng)) * step, py = (y + 0.5 + jitter(rng)) * step;
        std::snprintf(line, sizeof line, "%.4f %.4f 0 %d %d 120\n", px, py,
                      int(128 + 100 * std::sin(px * 7)), int(128 + 100 * std::sin(py * 11)));
        f << line;
      }
  }
  return test_scan::convertXyz(xyz, name, maxNodePoints);
}

RenderJob job(const fs::path& octree, const std::string& out, const glm::dvec3& eye,
              const glm::dvec3& target) {
  return test_scan::headlessJob(octree, out, eye, target);
}

bool isBackground(const float* p, const glm::vec3& bg) {
  return std::fabs(p[0] - bg.x) + std::fabs(p[1] - bg.y) + std::fabs(p[2] - bg.z) < 1e-3f;
}

double holeFraction(const Image& img, const glm::vec3& bg) {
  size_t holes = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) holes += isBackground(img.at(x, y), bg);
  return double(holes) / (double(img.width) * img.height);
}

}  // namespace

TEST(Splats, NoHolesOnAnEvenlySampledSurfaceAtAnyZoom) {
  // 250 x 250 points 1 cm apart on a 2.5 m square. From 8 cm to 0.8 m above its middle, looking
  // down steeply, the plane fills the whole frame: every pixel must be covered, whether the
  // finest drawn splats are the leaves' (up to ~25 px here) or an inner node's (~2 px).
  test::TempDir tmp;
  const fs::path octree = gridPlane(tmp, "plane", 250, 0.01, 8000);
  const glm::dvec3 centre(1.25, 1.25, 0);
  for (Splatting splatting : {Splatting::Hqs, Splatting::Basic})
    for (double h : {0.08, 0.2, 0.45, 0.8}) {
      const std::string out = tmp.file("zoom.exr");
      RenderJob j = job(octree, out, centre + glm::dvec3(0, -0.3 * h, h), centre);
      j.settings.splatting = splatting;
      renderHeadless(j);
      const Image img = readImage(out);
      const double holes = holeFraction(img, j.settings.background);
      if (holes > 0)
        writeImage(img, "splats-holes-" + std::string(splattingName(splatting)) + "-" +
                            std::to_string(int(h * 100)) + "cm.png");
      EXPECT_EQ(holes, 0.0) << splattingName(splatting) << " at " << h << " m";
    }
}

TEST(Splats, SizeFollowsTheMeasuredSpacingOfTheFinestDrawnNode) {
  // A plane in several levels, seen closely enough that the cut reaches the leaves (1 cm
  // spacing, the grid's step) everywhere in view. With splats of 0.5 spacings the discs do not
  // overlap, so the covered fraction is the disc area per point: pi/4 x 0.5^2 = 0.196 of the
  // surface. Were each point sized by its own node's spacing (the root's is 5 times the
  // leaves', with its points everywhere) the coverage would be far larger.
  test::TempDir tmp;
  const fs::path octree = gridPlane(tmp, "plane", 250, 0.01, 8000);
  const glm::dvec3 centre(1.25, 1.25, 0);
  const std::string out = tmp.file("size.exr");
  RenderJob j = job(octree, out, centre + glm::dvec3(0, -0.03, 0.12), centre);
  j.settings.splatting = Splatting::Basic;
  j.settings.sizeScale = 0.5f;
  j.settings.roundPoints = true;
  renderHeadless(j);
  const Image img = readImage(out);
  const double covered = 1.0 - holeFraction(img, j.settings.background);
  // The estimator measures this grid within a few percent of its step; a disc of a few pixels
  // rasterises to within ~15% of its area.
  const double expected = M_PI / 4 * 0.25;
  EXPECT_NEAR(covered, expected, 0.25 * expected);
  // Twice the scale, four times the area (still without overlap: 1 spacing).
  j.settings.sizeScale = 1.0f;
  renderHeadless(j);
  const double covered2 = 1.0 - holeFraction(readImage(out), j.settings.background);
  EXPECT_NEAR(covered2 / covered, 4.0, 0.8);
}

TEST(Splats, DefaultCameraFramesTheBounds) {
  // A flat strip, 600 x 265 x 20 m in national-grid coordinates, as airborne scans are.
  Box3d b;
  b.extend(500000, 5000000, 100);
  b.extend(500600, 5000265, 120);
  for (double aspect : {16.0 / 9.0, 1.0, 0.5}) {
    const double margin = 0.05;
    Camera c = Camera::framing(b, 60, aspect, 35, 30, margin);
    const glm::dmat4 clipFromWorld = c.clipFromWorld(aspect);
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int k = 0; k < 8; ++k) {
      const glm::dvec4 p =
          clipFromWorld * glm::dvec4((k & 4) ? b.max.x : b.min.x, (k & 2) ? b.max.y : b.min.y,
                                     (k & 1) ? b.max.z : b.min.z, 1.0);
      ASSERT_GT(p.w, 0);
      for (int a = 0; a < 2; ++a)
        lo[a] = std::min(lo[a], p[a] / p.w), hi[a] = std::max(hi[a], p[a] / p.w);
    }
    // Inside the frame less its margin, and touching both edges on one axis: no closer view
    // shows the whole box.
    for (int a = 0; a < 2; ++a) {
      EXPECT_GE(lo[a], -(1 - margin) - 1e-9);
      EXPECT_LE(hi[a], (1 - margin) + 1e-9);
    }
    const bool fillsX = lo[0] < -(1 - margin) + 1e-6 && hi[0] > (1 - margin) - 1e-6;
    const bool fillsY = lo[1] < -(1 - margin) + 1e-6 && hi[1] > (1 - margin) - 1e-6;
    EXPECT_TRUE(fillsX || fillsY) << "aspect " << aspect << ": x " << lo[0] << ".." << hi[0]
                                  << ", y " << lo[1] << ".." << hi[1];
  }
}
