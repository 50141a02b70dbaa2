// Picking and GPU clipping on headless renders of generated walls: the picked point is exactly the
// source point a brute-force search finds (nearest the pixel's centre on the front wall), to the
// millimetre in national-grid coordinates; clipping volumes hide what they remove in every
// rasteriser, a hidden point is never picked, and a volume that removes everything loads nothing.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>

#include "nestlight/frame/gpu_clip.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/viewer/headless.h"
#include "nestlight/viewer/image.h"
#include "small_scan.h"
#include "test_support.h"

using namespace nestlight;
using namespace nestlight::viewer;
namespace fs = std::filesystem;

namespace pick_clip_test {

// Two walls facing -y: the front one in the plane y = 0 (x in [0, 10], z in [0, 5]), a back one at
// y = 3 (wider, so it shows around the front one), every coordinate a whole millimetre plus
// `origin`. Returns the front wall's points in integer millimetres relative to `origin`.
struct Walls {
  fs::path octree;
  std::vector<std::array<int64_t, 3>> front;
  Vec3d origin;
};

Walls makeWalls(const test::TempDir& tmp, const Vec3d& origin, uint32_t maxNodePoints) {
  Walls w;
  w.origin = origin;
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int64_t> fx(0, 10000), fz(0, 5000), bx(-4000, 14000),
      bz(-2000, 7000);
  const fs::path xyz = tmp.path() / "walls.xyz";
  std::ofstream f(xyz);
  auto put = [&](int64_t x, int64_t y, int64_t z, int r, int g, int b) {
    char line[160];
    std::snprintf(line, sizeof line, "%.3f %.3f %.3f %d %d %d\n", origin.x + x / 1000.0,
                  origin.y + y / 1000.0, origin.z + z / 1000.0, r, g, b);
    f << line;
  };
  for (int i = 0; i < 20000; ++i) {
    const std::array<int64_t, 3> p{fx(rng), 0, fz(rng)};
    w.front.push_back(p);
    put(p[0], p[1], p[2], 220, 60, 40);
  }
  for (int i = 0; i < 20000; ++i) put(bx(rng), 3000, bz(rng), 40, 80, 220);
  f.close();
  w.octree = test_scan::convertXyz(xyz, "walls", maxNodePoints);
  return w;
}

RenderJob wallJob(const Walls& w, const test::TempDir& tmp, const std::string& name) {
  const glm::dvec3 o(w.origin.x, w.origin.y, w.origin.z);
  RenderJob j = test_scan::headlessJob(w.octree, tmp.file(name), o + glm::dvec3(5, -12, 2.5),
                                       o + glm::dvec3(5, 0, 2.5));
  j.budgets.spacingPixels = 0;  // every node: the brute force below searches every point
  return j;
}

// The front-wall point whose projection lies nearest the pixel's centre (x + 0.5, y + 0.5).
std::array<int64_t, 3> nearestFront(const Walls& w, const RenderJob& j, double x, double y,
                                    double* pixelDistance) {
  const frame::Camera& c = *j.camera;
  const double aspect = double(j.width) / j.height;
  const glm::dmat4 view = c.viewRotation(), proj = c.projection(aspect);
  double best = INFINITY;
  std::array<int64_t, 3> arg{};
  for (const auto& p : w.front) {
    const glm::dvec3 world(w.origin.x + p[0] / 1000.0, w.origin.y + p[1] / 1000.0,
                           w.origin.z + p[2] / 1000.0);
    const glm::dvec4 clip = proj * view * glm::dvec4(world - c.eye, 1.0);
    const double px = (clip.x / clip.w * 0.5 + 0.5) * j.width;
    const double py = (0.5 - clip.y / clip.w * 0.5) * j.height;
    const double d = std::hypot(px - (x + 0.5), py - (y + 0.5));
    if (d < best) best = d, arg = p;
  }
  *pixelDistance = best;
  return arg;
}

void expectPicksExact(const Vec3d& origin) {
  test::TempDir tmp;
  const Walls w = makeWalls(tmp, origin, 3000);  // several levels of nodes
  {
    OctreeReader r(w.octree);
    ASSERT_GE(r.allNodes().size(), 5u) << "the walls should span several depths";
  }
  RenderJob j = wallJob(w, tmp, "walls.png");
  const std::vector<std::array<double, 2>> pixels = {{64, 48}, {40, 52}, {90, 44}, {70, 58}};
  j.picks = pixels;
  j.picks.push_back({3, 2});  // above both walls: background
  const auto frames = renderHeadless(j);
  ASSERT_EQ(frames.size(), 1u);
  ASSERT_TRUE(frames[0].complete);
  ASSERT_EQ(frames[0].picks.size(), pixels.size() + 1);
  for (size_t i = 0; i < pixels.size(); ++i) {
    SCOPED_TRACE("pixel " + std::to_string(int(pixels[i][0])) + "," +
                 std::to_string(int(pixels[i][1])));
    const auto& got = frames[0].picks[i];
    ASSERT_TRUE(got.has_value());
    double dist = 0;
    const auto want = nearestFront(w, j, pixels[i][0], pixels[i][1], &dist);
    // Exact to the millimetre: the octree's integers, not the GPU's floats.
    EXPECT_EQ(std::llround((got->position.x - origin.x) * 1000), want[0]);
    EXPECT_EQ(std::llround((got->position.y - origin.y) * 1000), want[1]);
    EXPECT_EQ(std::llround((got->position.z - origin.z) * 1000), want[2]);
    EXPECT_NEAR(got->pixelDistance, dist, 1e-6);
    EXPECT_EQ(got->attributes["rgb"][0].get<int>() >> 8, 220) << got->attributes.dump();
  }
  EXPECT_FALSE(frames[0].picks.back().has_value()) << "the background picked a point";
}

TEST(Picking, NearestPointOfTheFrontWallExactly) {
  expectPicksExact({0, 0, 0});
}

// Six-digit eastings, seven-digit northings: float32 would be off by decimetres here.
TEST(Picking, NationalGridCoordinatesToTheMillimetre) {
  expectPicksExact({512345.0, 5412345.0, 310.0});
}

// The snap of a measurement's vertex (frame::nearestPoint): the point of the given nodes nearest a
// target in 3D, exactly as a brute force over the source finds it; nothing beyond the distance
// asked; nodes already searched are skipped (a vertex refines only with new nodes); clipped
// points are never snapped to.
TEST(Picking, NearestPointSnapsExactlyAndOnlyToNewNodes) {
  const Vec3d o{512345.0, 5412345.0, 310.0};
  test::TempDir tmp;
  const Walls w = makeWalls(tmp, o, 3000);
  OctreeReader reader(w.octree);
  std::vector<streaming::DrawNode> nodes;
  for (const auto& [key, e] : reader.allNodes()) {
    streaming::DrawNode n;
    n.key = key;
    n.numPoints = e.numPoints;
    n.worldBounds = reader.metadata().nodeBounds(key.level, key.x, key.y, key.z);
    nodes.push_back(n);
  }
  const Vec3d target{o.x + 3.2104, o.y + 0.05, o.z + 1.7771};
  double best = INFINITY;
  std::array<int64_t, 3> want{};
  for (const auto& p : w.front) {
    const double d =
        std::hypot(p[0] / 1000.0 - 3.2104, p[1] / 1000.0 - 0.05, p[2] / 1000.0 - 1.7771);
    if (d < best) best = d, want = p;
  }
  std::vector<NodeKey> searched;
  const auto got = frame::nearestPoint(reader, nodes, target, 1.0, nullptr, &searched);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(std::llround((got->position.x - o.x) * 1000), want[0]);
  EXPECT_EQ(std::llround((got->position.z - o.z) * 1000), want[2]);
  EXPECT_NEAR(got->depth, best, 1e-9);
  EXPECT_FALSE(searched.empty());
  EXPECT_LT(searched.size(), nodes.size()) << "every node was read for a 1 m search";
  // Refining (within the current snap distance, searched nodes skipped) finds nothing nearer.
  const size_t searchedBefore = searched.size();
  EXPECT_FALSE(
      frame::nearestPoint(reader, nodes, target, got->depth, nullptr, &searched).has_value());
  EXPECT_EQ(searched.size(), searchedBefore) << "a node was searched twice or needlessly";
  // Nothing within a distance shorter than the nearest point's.
  EXPECT_FALSE(frame::nearestPoint(reader, nodes, target, 0.5 * best, nullptr).has_value());
  // A box hiding the nearest point: the next one is found, farther.
  ClipSet hide;
  ClipVolume box = ClipVolume::box(got->position, {1e-3, 1e-3, 1e-3});
  box.mode = ClipVolume::Mode::Outside;
  hide.volumes.push_back(box);
  const auto next = frame::nearestPoint(reader, nodes, target, 1.0, &hide);
  ASSERT_TRUE(next.has_value());
  EXPECT_GT(next->depth, got->depth);
}

// Coverage of the columns [x0, x1) of an image: pixels not of the background colour.
size_t covered(const Image& img, int x0, int x1) {
  size_t n = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = x0; x < x1; ++x) {
      const float* p = img.at(x, y);
      if (std::fabs(p[0] - img.at(0, 0)[0]) + std::fabs(p[1] - img.at(0, 0)[1]) +
              std::fabs(p[2] - img.at(0, 0)[2]) >
          0.02f)
        ++n;
    }
  return n;
}
// Red (the front wall) pixels in columns [x0, x1).
size_t red(const Image& img, int x0, int x1) {
  size_t n = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = x0; x < x1; ++x) {
      const float* p = img.at(x, y);
      if (p[0] > 0.5f && p[2] < 0.4f) ++n;
    }
  return n;
}

struct RasteriserCase {
  const char* name;
  frame::Rasteriser rasteriser;
  frame::Splatting splatting;
};

void PrintTo(const RasteriserCase& c, std::ostream* os) {
  *os << c.name;
}

class ClipRasterisers : public ::testing::TestWithParam<RasteriserCase> {};

// A box keeping the front wall's left half (x < 5 m) and nothing of the back wall: the right half
// of the image shows nothing, the left half the red wall as without clipping. In national-grid
// coordinates, so the GPU's volumes are tested relative to the eye.
TEST_P(ClipRasterisers, BoxHidesWhatItRemoves) {
  const Vec3d o{512345.0, 5412345.0, 310.0};
  test::TempDir tmp;
  const Walls w = makeWalls(tmp, o, 3000);
  RenderJob j = wallJob(w, tmp, "full.png");
  j.settings.rasteriser = GetParam().rasteriser;
  j.settings.splatting = GetParam().splatting;
  if (j.settings.rasteriser == frame::Rasteriser::Compute) j.settings.fixedPointSize = 1;
  renderHeadless(j);
  const Image full = readImage(j.output);
  ClipSet set;
  set.volumes.push_back(ClipVolume::box({o.x + 2.5, o.y, o.z + 2.5}, {5, 1, 6}));
  j.settings.clip = std::make_shared<const ClipSet>(set);
  j.output = tmp.file("clipped.png");
  // The pixel under the centre of the removed half: the clip hides it, so nothing is there.
  j.picks = {{96, 48}, {30, 48}};
  const auto frames = renderHeadless(j);
  const Image clipped = readImage(j.output);
  // x = 5 m projects to column 64; splats reach a few pixels either side of it.
  EXPECT_GT(red(full, 70, 128), 500u);
  EXPECT_EQ(covered(clipped, 70, 128), 0u) << "the clipped half is drawn";
  const size_t fullLeft = red(full, 0, 58), clippedLeft = red(clipped, 0, 58);
  EXPECT_GT(fullLeft, 500u);
  EXPECT_NEAR(double(clippedLeft), double(fullLeft), 0.01 * fullLeft);
  EXPECT_EQ(covered(clipped, 0, 20), 0u) << "the back wall's left edge is drawn";
  ASSERT_EQ(frames[0].picks.size(), 2u);
  EXPECT_FALSE(frames[0].picks[0].has_value()) << "a clipped point was picked";
  ASSERT_TRUE(frames[0].picks[1].has_value());
  EXPECT_LT(frames[0].picks[1]->position.x, o.x + 5);
}

INSTANTIATE_TEST_SUITE_P(
    Rasterisers, ClipRasterisers,
    ::testing::Values(RasteriserCase{"hqs", frame::Rasteriser::Points, frame::Splatting::Hqs},
                      RasteriserCase{"basic", frame::Rasteriser::Points, frame::Splatting::Basic},
                      RasteriserCase{"compute", frame::Rasteriser::Compute, frame::Splatting::Hqs}),
    [](const auto& info) { return std::string(info.param.name); });

// Outside mode through a polygon: a plan-view square around the front wall's middle removes it
// there, and the back wall shows through; picking there finds the back wall.
TEST(Clipping, OutsidePolygonShowsWhatIsBehind) {
  test::TempDir tmp;
  const Walls w = makeWalls(tmp, {0, 0, 0}, 3000);
  RenderJob j = wallJob(w, tmp, "hole.png");
  ClipVolume hole = ClipVolume::polygon({{4, -1}, {6, -1}, {6, 1}, {4, 1}});
  hole.mode = ClipVolume::Mode::Outside;
  ClipSet set;
  set.volumes.push_back(hole);
  j.settings.clip = std::make_shared<const ClipSet>(set);
  j.picks = {{64, 48}};
  const auto frames = renderHeadless(j);
  const Image img = readImage(j.output);
  EXPECT_EQ(red(img, 60, 68), 0u) << "the hole shows the front wall";
  EXPECT_GT(red(img, 30, 55), 500u);
  ASSERT_TRUE(frames[0].picks[0].has_value());
  EXPECT_DOUBLE_EQ(frames[0].picks[0]->position.y, 3.0) << "not the back wall";
}

// A box far from the scan: nothing is drawn, nothing is loaded, the frame is still complete.
TEST(Clipping, VolumeThatRemovesEverythingLoadsNothing) {
  test::TempDir tmp;
  const Walls w = makeWalls(tmp, {0, 0, 0}, 3000);
  RenderJob j = wallJob(w, tmp, "empty.png");
  ClipSet set;
  set.volumes.push_back(ClipVolume::box({100, 100, 100}, {1, 1, 1}));
  j.settings.clip = std::make_shared<const ClipSet>(set);
  j.picks = {{64, 48}};
  const auto frames = renderHeadless(j);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_TRUE(frames[0].complete);
  EXPECT_EQ(frames[0].stats.cutNodes, 0u);
  EXPECT_EQ(frames[0].stats.bytesRead, 0u);
  EXPECT_EQ(covered(readImage(j.output), 0, 128), 0u);
  EXPECT_FALSE(frames[0].picks[0].has_value());
}

// More volumes than the GPU's block holds: an error that says so, before anything is drawn.
TEST(Clipping, TooManyVolumesForTheGpuIsAnError) {
  ClipSet set;
  for (int i = 0; i < NL_MAX_CLIP_VOLUMES + 1; ++i)
    set.volumes.push_back(ClipVolume::box({double(i), 0, 0}, {1, 1, 1}));
  const std::string msg = test::errorOf([&] { frame::encodeClipBlock(set, {}); }).what();
  EXPECT_NE(msg.find("at most 16"), std::string::npos) << msg;
}

// The encoding keeps national-grid boxes exact relative to the frame's origin: a box's own
// coordinates of points just inside and just outside its faces, computed as the shader does.
TEST(Clipping, EncodedBoxIsExactRelativeToTheOrigin) {
  const Vec3d c{512345.25, 5412345.75, 310.5};
  ClipSet set;
  set.volumes.push_back(ClipVolume::box(c, {2, 4, 6}, {0, 0, 30}));
  const Vec3d eye{c.x - 20, c.y - 30, c.z + 5};
  const frame::ClipBlock b = frame::encodeClipBlock(set, eye);
  const glm::mat4& m = b.clipVolumes[0].boxFromFrame;
  const double a = glm::radians(30.0);
  for (double s : {0.999, 1.001}) {
    // Along the box's own x axis (rotated 30 degrees about z), s half-widths from the centre.
    const glm::vec3 p(float(c.x - eye.x + s * std::cos(a)), float(c.y - eye.y + s * std::sin(a)),
                      float(c.z - eye.z));
    const glm::vec4 q = m * glm::vec4(p, 1.0f);
    EXPECT_NEAR(q.x, s, 1e-4);
    EXPECT_EQ(std::abs(q.x) <= 1.0f, s < 1);
  }
}

}  // namespace pick_clip_test
