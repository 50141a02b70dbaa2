// Image tests: small headless renders (EGL; llvmpipe in CI) of converted scans, compared with
// goldens in tests/goldens/. On a failure the rendered image and a diff image are written beside
// the test binary (render-<name>.png, render-<name>-diff.png). scripts/update_goldens.sh
// re-renders the goldens (NESTLIGHT_UPDATE_GOLDENS=1).
#include <cstdlib>
#include <fstream>
#include <regex>

#include "golden.h"
#include "nestlight/converters/builder.h"
#include "nestlight/converters/reader.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/gi/hdr_image.h"
#include "nestlight/gl/context.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/viewer/headless.h"
#include "nestlight/viewer/image.h"
#include "test_support.h"

using namespace nestlight;
using namespace nestlight::viewer;
using namespace nestlight::frame;
namespace fs = std::filesystem;

namespace {
using nestlight::test::expectMatchesGolden;

void convert(std::vector<std::unique_ptr<PointReader>> readers, const fs::path& out) {
  BuildOptions o;
  o.output = out;
  o.overwrite = true;
  o.progress = ProgressMode::Quiet;
  buildOctree(std::move(readers), o);
}

fs::path convertShared(const std::string& rel, const test::TempDir& tmp) {
  std::vector<std::unique_ptr<PointReader>> r;
  r.push_back(openReader((::nestlight::test::sharedData() / rel).string()));
  const fs::path out = tmp.path() / (fs::path(rel).stem().string() + ".octree");
  convert(std::move(r), out);
  return out;
}

// A seeded synthetic scan converted into `tmp`/`name`.
fs::path syntheticOctree(const test::TempDir& tmp, const std::string& name, uint64_t points,
                         uint64_t seed = 1, Vec3d origin = {0, 0, 0}) {
  SyntheticSpec spec;
  spec.points = points;
  spec.seed = seed;
  spec.origin = origin;
  std::vector<std::unique_ptr<PointReader>> r;
  r.push_back(openSynthetic(spec));
  convert(std::move(r), tmp.path() / name);
  return tmp.path() / name;
}

RenderJob smallJob(const fs::path& octree, const std::string& output) {
  RenderJob j;
  j.octree = octree;
  j.output = output;
  j.width = 160;
  j.height = 120;
  j.waitComplete = true;
  j.timeoutSeconds = 60;
  j.quiet = true;
  return j;
}

double coverage(const Image& img, const glm::vec3& background) {
  size_t covered = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const float* p = img.at(x, y);
      if (std::fabs(p[0] - background.x) + std::fabs(p[1] - background.y) +
              std::fabs(p[2] - background.z) >
          0.02f)
        ++covered;
    }
  return double(covered) / (double(img.width) * img.height);
}

}  // namespace

// Goldens: llvmpipe is deterministic for a given Mesa and LLVM; the tolerance (3/255 per channel
// on at most 0.5% of pixels) absorbs rounding changes at splat borders between LLVM versions.
// Re-made when splats became sized by the measured spacing of the finest drawn node, HQS the
// default, the default camera a fit of the bounds to the frame, and eye-dome lighting stopped
// dropping points nearer than one world unit (the lion is metre-sized: its near side was lost).
// lion_points re-made when the point view's G-buffer became linear: high-quality splatting now
// blends colours in linear light (0.8% of pixels, at high-contrast splat blends, changed by up to
// 30/255; the basic and compute goldens were unchanged).
TEST(RenderGolden, LionPoints) {
  NL_REQUIRE_SHARED("scans/lion_takanawa.las");
  test::TempDir tmp;
  RenderJob j = smallJob(convertShared("scans/lion_takanawa.las", tmp), tmp.file("lion.png"));
  auto frames = renderHeadless(j);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_TRUE(frames[0].complete);
  expectMatchesGolden(j.output, "lion_points", 3.f / 255, 0.005);
}

TEST(RenderGolden, LionCompute) {
  NL_REQUIRE_SHARED("scans/lion_takanawa.las");
  test::TempDir tmp;
  RenderJob j =
      smallJob(convertShared("scans/lion_takanawa.las", tmp), tmp.file("lion_compute.png"));
  j.settings.rasteriser = Rasteriser::Compute;
  j.settings.fixedPointSize = 1;
  renderHeadless(j);
  expectMatchesGolden(j.output, "lion_compute", 3.f / 255, 0.005);
}

TEST(RenderGolden, AutzenElevation) {
  NL_REQUIRE_SHARED("scans/autzen_trim.las");
  test::TempDir tmp;
  RenderJob j = smallJob(convertShared("scans/autzen_trim.las", tmp), tmp.file("autzen.png"));
  j.colour = frame::ColourMode::Elevation;
  j.elevation = 50;
  renderHeadless(j);
  expectMatchesGolden(j.output, "autzen_elevation", 3.f / 255, 0.005);
}

// The two rasterisers agree where both draw one pixel per point: differences come only from
// pixels where several points fall within 1% of the nearest depth (the compute path averages
// them, GL_POINTS keeps the first) and from sub-pixel rounding at pixel borders.
TEST(Render, ComputeAndPointsPathsAgree) {
  NL_REQUIRE_SHARED("scans/lion_takanawa.las");
  test::TempDir tmp;
  const fs::path oct = convertShared("scans/lion_takanawa.las", tmp);
  RenderJob a = smallJob(oct, tmp.file("a.png"));
  a.width = 320, a.height = 240;
  a.settings.fixedPointSize = 1;
  a.settings.edlStrength = 0;
  RenderJob b = a;
  b.output = tmp.file("b.png");
  b.settings.rasteriser = Rasteriser::Compute;
  renderHeadless(a);
  renderHeadless(b);
  Image ia = readImage(a.output), ib = readImage(b.output);
  // Coverage must match closely: both paths put each point in the same pixel.
  EXPECT_NEAR(coverage(ia, a.settings.background), coverage(ib, b.settings.background), 0.01);
  ImageDiff d = compareImages(ia, ib, 24.f / 255);
  // Measured on llvmpipe: 1.7% of pixels.
  EXPECT_LE(d.fraction, 0.05) << d.differing << " pixels differ";
}

// A tiled render equals the single-framebuffer one: tiles reuse the big image's projection, and
// their margins give eye-dome lighting its neighbours.
TEST(Render, TiledEqualsUntiled) {
  test::TempDir tmp;
  const fs::path oct = syntheticOctree(tmp, "s.octree", 200'000, 7);
  for (Splatting splatting : {Splatting::Basic, Splatting::Hqs}) {
    RenderJob a = smallJob(oct, tmp.file("whole.png"));
    a.width = 300, a.height = 200;
    a.settings.splatting = splatting;
    RenderJob b = a;
    b.output = tmp.file("tiled.png");
    b.settings.maxTile = 64;
    renderHeadless(a);
    renderHeadless(b);
    ImageDiff d = compareImages(readImage(a.output), readImage(b.output), 1.f / 255);
    // A tile's projection (and the guard band's wider viewport) rounds differently in its last
    // bits from the whole image's, which moves a splat's edge across a pixel centre now and
    // then, and HQS weights with it: a handful of pixels (11 of 60,000 measured on llvmpipe).
    const size_t allowed = 20;
    EXPECT_LE(d.differing, allowed)
        << splattingName(splatting) << ": max channel error " << d.maxChannel;
  }
}

// National-grid coordinates: the same scan 5,000 km away, seen by the same camera shifted by
// the same amount, gives the same image (positions reach the GPU relative to the eye).
TEST(Render, NationalGridDoesNotJitter) {
  test::TempDir tmp;
  const Vec3d far{500000, 5000000, 100};
  const fs::path local = syntheticOctree(tmp, "local.octree", 150'000, 11);
  const fs::path grid = syntheticOctree(tmp, "grid.octree", 150'000, 11, far);
  Camera c;
  c.eye = {130, -40, 60};
  c.target = {50, 50, 10};
  // Every point drawn (no LOD): the two octrees' cubes sit differently around the points, so
  // their node samples differ; all points together do not.
  RenderJob a = smallJob(local, tmp.file("local.png"));
  a.camera = c;
  a.width = 320, a.height = 240;
  a.budgets.spacingPixels = 0;
  a.budgets.points = 1'000'000;
  a.settings.fixedPointSize = 2;  // splat sizes follow node levels, which differ between the two
  // Nearest-splat: HQS weights move with the last float bits of a position, which is not what
  // this test is about (node offsets reaching the GPU exactly).
  a.settings.splatting = Splatting::Basic;
  RenderJob b = a;
  b.octree = grid;
  b.output = tmp.file("grid.png");
  c.eye += glm::dvec3(far.x, far.y, far.z);
  c.target += glm::dvec3(far.x, far.y, far.z);
  b.camera = c;
  renderHeadless(a);
  renderHeadless(b);
  Image ia = readImage(a.output), ib = readImage(b.output);
  EXPECT_GT(coverage(ia, a.settings.background), 0.2);
  ImageDiff d = compareImages(ia, ib, 2.f / 255);
  // Positions reach the GPU as (node origin - eye) in double, then float, plus small node-local
  // floats: the far scan draws exactly like the near one. Float world positions would be off by
  // ~0.5 m at y = 5e6 and change most pixels.
  EXPECT_EQ(d.differing, 0u) << "max channel error " << d.maxChannel;
}

TEST(Render, ExrOutputIsLinear) {
  test::TempDir tmp;
  const fs::path oct = syntheticOctree(tmp, "s.octree", 50'000, 1);
  RenderJob a = smallJob(oct, tmp.file("x.png"));
  RenderJob b = a;
  b.output = tmp.file("x.exr");
  renderHeadless(a);
  renderHeadless(b);
  // readImage converts EXR back to display values: both files hold the same picture.
  ImageDiff d = compareImages(readImage(a.output), readImage(b.output), 1.5f / 255);
  EXPECT_EQ(d.differing, 0u) << d.maxChannel;
}

// --colour hdr: the octree's HDR colour layer drawn in linear colour, so an EXR holds it whole,
// far above 1, through both rasterisers and both splattings. The layer is one colour everywhere
// (every way of averaging splats then gives it back): each covered pixel must hold it within
// RGB9E5's rounding (half a step; the step is 2^-9 of the power of two above the largest
// channel, so at most the largest / 512) plus two half-float roundings (G-buffer and output,
// 2^-11 each). A scan without the layer is refused with the layer named.
TEST(Render, HdrColourLayerIsWrittenLinearlyToExr) {
  test::TempDir tmp;
  const fs::path oct = syntheticOctree(tmp, "s.octree", 40'000, 2);
  RenderJob j = smallJob(oct, tmp.file("h.exr"));
  j.colour = frame::ColourMode::Hdr;
  {
    const Error e = test::errorOf([&] { renderHeadless(j); });
    EXPECT_NE(std::string(e.what()).find("no colour layer 'hdr'"), std::string::npos) << e.what();
  }
  const std::array<float, 3> want = {300.0f, 150.0f, 37.5f};
  test::writeColourLayer(oct, "hdr", [&](const NodeKey&, size_t) { return want; });
  j.settings.edlStrength = 0;
  struct Case {
    Rasteriser r;
    Splatting s;
    bool atomic64;  // compute: the one-pass 64-bit variant where the GPU has it (llvmpipe never)
  };
  for (Case c : {Case{Rasteriser::Points, Splatting::Basic, true},
                 Case{Rasteriser::Points, Splatting::Hqs, true},
                 Case{Rasteriser::Compute, Splatting::Basic, true},
                 Case{Rasteriser::Compute, Splatting::Basic, false}}) {
    j.settings.rasteriser = c.r;
    j.settings.splatting = c.s;
    j.settings.allowAtomic64 = c.atomic64;
    j.settings.fixedPointSize = c.r == Rasteriser::Compute ? 1.0f : 0.0f;
    renderHeadless(j);
    const gi::HdrImage img = gi::readHdrImage(j.output);
    size_t covered = 0;
    double worst = 0;
    for (size_t p = 0; p < img.pixels(); ++p) {
      if (img.rgb[3 * p] < 1.0f) continue;  // the background (linear, below 0.01)
      ++covered;
      for (int k = 0; k < 3; ++k)
        worst = std::max(worst, std::abs(double(img.rgb[3 * p + k]) - want[k]) /
                                    (want[0] / 512.0 + want[k] / 1024.0));
    }
    const std::string name =
        std::string(rasteriserName(c.r)) + "/" + splattingName(c.s) + (c.atomic64 ? "" : "/32-bit");
    EXPECT_GT(covered, img.pixels() / 10) << name;
    EXPECT_LE(worst, 1.0) << name << ": worst error in units of the tolerance";
  }
}

TEST(Render, UnknownFormatVersionFailsBeforeGl) {
  test::TempDir tmp;
  const fs::path oct = syntheticOctree(tmp, "s.octree", 1000, 1);
  std::string meta = test::readFile((oct / "metadata.json").string());
  const std::string before = meta;
  meta = std::regex_replace(meta, std::regex(R"("version":\s*\d+)"), "\"version\": 99");
  ASSERT_NE(meta, before);
  test::writeFile((oct / "metadata.json").string(), meta);
  Error e = test::errorOf([&] { renderHeadless(smallJob(oct, tmp.file("x.png"))); });
  EXPECT_NE(std::string(e.what()).find("version"), std::string::npos) << e.what();
  Error e2 = test::errorOf([&] { renderHeadless(smallJob(tmp.path(), tmp.file("x.png"))); });
  EXPECT_NE(std::string(e2.what()).find("metadata.json"), std::string::npos) << e2.what();
}

TEST(Render, CameraPathWritesSequenceAndStats) {
  test::TempDir tmp;
  const fs::path oct = syntheticOctree(tmp, "s.octree", 100'000, 1);
  test::writeFile(
      tmp.file("path.json"),
      R"({"fps": 4, "fov": 50, "keyframes": [{"time": 0, "eye": [150, -50, 80], "target": [50, 50, 0]},
                      {"time": 1, "eye": [50, -100, 60], "target": [50, 50, 0]}]})");
  RenderJob j = smallJob(oct, tmp.file("f_%04d.png"));
  j.path = gi::loadCameraPath(tmp.file("path.json"));
  j.statsCsv = tmp.file("stats.csv");
  auto frames = renderHeadless(j);
  ASSERT_EQ(frames.size(), 5u);
  for (int f = 0; f < 5; ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "f_%04d.png", f);
    EXPECT_TRUE(fs::exists(tmp.file(name))) << name;
    EXPECT_TRUE(frames[size_t(f)].complete);
  }
  std::ifstream csv(j.statsCsv);
  std::string line;
  int lines = 0;
  while (std::getline(csv, line)) ++lines;
  EXPECT_EQ(lines, 6);  // header + 5 frames
  test::writeFile(tmp.file("bad.json"),
                  R"({"keyframes": [{"time": 0, "eye": [1, 2], "target": [0, 0, 0]}]})");
  Error e = test::errorOf([&] { gi::loadCameraPath(tmp.file("bad.json")); });
  EXPECT_NE(std::string(e.what()).find("keyframes[0].eye"), std::string::npos) << e.what();
}

// The OSMesa fallback draws the same picture as EGL (both are llvmpipe here).
TEST(Render, OsMesaFallbackMatchesEgl) {
  test::TempDir tmp;
  const fs::path oct = syntheticOctree(tmp, "s.octree", 60'000, 1);
  RenderJob a = smallJob(oct, tmp.file("egl.png"));
  RenderJob b = a;
  b.output = tmp.file("osmesa.png");
  ::setenv("NESTLIGHT_GL_PLATFORM", "surfaceless", 1);
  if (!gl::createHeadlessContext()->isSoftware()) {
    ::unsetenv("NESTLIGHT_GL_PLATFORM");
    GTEST_SKIP() << "EGL runs on a GPU here: the images of two rasterisers are not compared "
                    "pixel for pixel";
  }
  renderHeadless(a);
  ::setenv("NESTLIGHT_GL_PLATFORM", "osmesa", 1);
  try {
    renderHeadless(b);
  } catch (const Error& e) {
    ::unsetenv("NESTLIGHT_GL_PLATFORM");
    if (std::string(e.what()).find("libOSMesa is not installed") != std::string::npos)
      GTEST_SKIP() << "no OSMesa on this machine: " << e.what();
    throw;
  }
  ::unsetenv("NESTLIGHT_GL_PLATFORM");
  ImageDiff d = compareImages(readImage(a.output), readImage(b.output), 1.f / 255);
  EXPECT_EQ(d.differing, 0u) << d.maxChannel;
}

// The platform-by-platform failure report itself cannot be provoked on a machine that has Mesa.
TEST(Render, UnknownGlPlatformIsRejectedWithTheChoices) {
  ::setenv("NESTLIGHT_GL_PLATFORM", "bogus", 1);
  Error e = test::errorOf([] { gl::createHeadlessContext(); });
  ::unsetenv("NESTLIGHT_GL_PLATFORM");
  EXPECT_NE(std::string(e.what()).find("device, surfaceless or osmesa"), std::string::npos)
      << e.what();
}

// A damaged payload while rendering: the node is marked bad and logged, the frame completes
// with the rest of the cut.
TEST(Render, DamagedPayloadIsSkippedAndRenderingGoesOn) {
  test::TempDir tmp;
  const fs::path oct = syntheticOctree(tmp, "s.octree", 200'000, 1);
  uint64_t offset = 0, size = 0;
  {
    OctreeReader reader(oct);
    for (auto& [key, e] : reader.allNodes())
      if (key.level == 1 && e.byteSize > 64) {
        offset = e.byteOffset, size = e.byteSize;
        break;
      }
  }
  ASSERT_GT(size, 0u);
  {
    std::fstream f((oct / "octree.bin").string(), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(std::streamoff(offset + size / 2));
    const char junk[8] = {'d', 'a', 'm', 'a', 'g', 'e', 'd', '!'};
    f.write(junk, sizeof junk);
  }
  RenderJob j = smallJob(oct, tmp.file("damaged.png"));
  j.budgets.spacingPixels = 0;
  std::vector<RenderedFrame> frames;
  ASSERT_NO_THROW(frames = renderHeadless(j));
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_TRUE(frames[0].complete);
  EXPECT_EQ(frames[0].stats.badNodes, 1u);
  EXPECT_GT(frames[0].stats.drawNodes, 0u);
  EXPECT_TRUE(fs::exists(j.output));
}
