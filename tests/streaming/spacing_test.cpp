// The refinement criterion and the measured point spacing the draw list carries: a converged
// cut's finest drawn nodes have spacings that project to at most `spacingPixels`; each drawn
// node carries the spacing the builder measured for it; an octree of format version 1 (no
// measured spacing) still opens, with the nominal spacing in its place.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "nestlight/octree/checksum.h"
#include "nestlight/octree/hierarchy.h"
#include "streaming_support.h"
#include "test_support.h"

using namespace nestlight;
using namespace nestlight::streaming;
namespace fs = std::filesystem;

namespace {

SyntheticSpec surfaces(uint64_t points) {
  SyntheticSpec spec;
  spec.points = points;
  spec.seed = 3;
  return spec;
}

Budgets generous() {
  Budgets b;
  b.points = 50'000'000;
  b.gpuBytes = 4ull << 30;
  b.uploadBytesPerFrame = 1ull << 30;
  b.spacingPixels = 1.0;
  return b;
}

// Distance from the eye to a node's cube clipped to the scan's bounds, minus nothing: the
// nearest any of its points can be (the cut uses the bounding sphere, which is nearer still).
double nearestDistance(const DrawNode& n, const Box3d& bounds, const glm::dvec3& eye) {
  double d2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double lo = std::max(n.worldBounds.min[a], bounds.min[a]),
                 hi = std::min(n.worldBounds.max[a], bounds.max[a]);
    const double e = a == 0 ? eye.x : a == 1 ? eye.y : eye.z;
    const double d = e < lo ? lo - e : e > hi ? e - hi : 0;
    d2 += d * d;
  }
  return std::sqrt(d2);
}

// Child `i`'s cube clipped to the scan's bounds, as the cut culls it.
Box3d childBox(const DrawNode& n, int i, const Box3d& bounds) {
  const NodeKey k = n.key.child(i);
  Box3d b;
  for (int a = 0; a < 3; ++a) {
    const double half = 0.5 * (n.worldBounds.max[a] - n.worldBounds.min[a]);
    const uint32_t bit = a == 0 ? (k.x & 1) : a == 1 ? (k.y & 1) : (k.z & 1);
    const double lo = n.worldBounds.min[a] + bit * half;
    b.min[a] = std::max(lo, bounds.min[a]);
    b.max[a] = std::min(lo + half, bounds.max[a]);
  }
  return b;
}

}  // namespace

TEST(RefinementCriterion, ConvergedCutsFinestSpacingProjectsToAboutOnePixel) {
  test::TempDir tmp;
  const Metadata meta = test::buildSyntheticOctree(tmp.path() / "o", surfaces(400'000), 2000);
  OctreeReader reader(tmp.path() / "o");
  MemoryStore store(reader.metadata());
  Streamer s(reader, store, generous());
  const glm::dvec3 c = test::boundsCenter(meta);
  const double size = meta.bounds.max.x - meta.bounds.min.x;
  for (const glm::dvec3& eye : {c + glm::dvec3(size * 0.9, size * 0.4, size * 0.5),
                                c + glm::dvec3(0, -size * 0.3, size * 0.1)}) {
    const View v = test::camera(eye, c);
    const Frustum frustum(v.clipFromWorld);
    ASSERT_GT(test::runUntilComplete(s, v, 5000), 0);
    std::set<NodeKey> drawn;
    for (const DrawNode& n : s.drawList()) drawn.insert(n.key);
    size_t finest = 0;
    for (const DrawNode& n : s.drawList()) {
      const auto e = reader.peek(n.key);
      ASSERT_TRUE(e);
      bool childDrawn = false;
      for (int i = 0; i < 8; ++i) childDrawn |= drawn.count(n.key.child(i)) > 0;
      bool childVisible = false;  // children all outside the view are rightly not drawn
      for (int i = 0; i < 8; ++i)
        if (e->childMask & (1u << i))
          childVisible |= frustum.intersects(childBox(n, i, meta.bounds));
      if (childDrawn || !childVisible) continue;  // refined, or nothing finer in view
      ++finest;
      // Not refined although children exist: its spacing must project to at most one pixel at
      // the node's bounding sphere, hence at most ~1 px (the sphere is nearer than any point).
      const double px = v.projectedPixels(n.spacing, nearestDistance(n, meta.bounds, eye));
      EXPECT_LE(px, 1.0 + 1e-9) << n.key.name();
    }
    EXPECT_GT(finest, 0u) << "the view should stop refining somewhere";
    // And refinement went as deep as the criterion asks: a drawn node whose spacing projects
    // to more than 1 px at its far side was refined (where it has children).
    for (const DrawNode& n : s.drawList()) {
      const auto e = reader.peek(n.key);
      const glm::dvec3 mid =
          0.5 * (glm::dvec3(n.worldBounds.min.x, n.worldBounds.min.y, n.worldBounds.min.z) +
                 glm::dvec3(n.worldBounds.max.x, n.worldBounds.max.y, n.worldBounds.max.z));
      const double far = glm::length(mid - eye) +
                         glm::length(mid - glm::dvec3(n.worldBounds.min.x, n.worldBounds.min.y,
                                                      n.worldBounds.min.z));
      if (e->childMask == 0 || v.projectedPixels(n.spacing, far) <= 1.0) continue;
      bool childVisible = false;
      for (int i = 0; i < 8; ++i)
        if (e->childMask & (1u << i))
          childVisible |= frustum.intersects(childBox(n, i, meta.bounds));
      if (!childVisible) continue;
      bool childDrawn = false;
      for (int i = 0; i < 8; ++i) childDrawn |= drawn.count(n.key.child(i)) > 0;
      EXPECT_TRUE(childDrawn) << n.key.name()
                              << " projects its spacing to more than 1 px yet was not refined";
    }
  }
}

TEST(MeasuredSpacing, DrawListCarriesTheBuildersMeasurement) {
  test::TempDir tmp;
  const Metadata meta = test::buildSyntheticOctree(tmp.path() / "o", surfaces(200'000), 2000);
  EXPECT_EQ(meta.version, kFormatVersion);
  OctreeReader reader(tmp.path() / "o");
  MemoryStore store(reader.metadata());
  Streamer s(reader, store, generous());
  const glm::dvec3 c = test::boundsCenter(meta);
  const double size = meta.bounds.max.x - meta.bounds.min.x;
  const View v = test::camera(c + glm::dvec3(size * 0.2, size * 0.1, size * 0.1), c);
  ASSERT_GT(test::runUntilComplete(s, v, 5000), 0);
  size_t measured = 0;
  for (const DrawNode& n : s.drawList()) {
    const auto e = reader.peek(n.key);
    ASSERT_TRUE(e);
    if (e->spacingCode == 0) {
      EXPECT_EQ(n.pointSpacing, n.spacing);  // too few points to measure: the nominal spacing
      continue;
    }
    ++measured;
    EXPECT_DOUBLE_EQ(n.pointSpacing, decodeSpacing(e->spacingCode, n.spacing));
    // Inner nodes are Poisson-disk samples at the nominal spacing or wider (the builder widens
    // the radius until a node fits its point limit); leaves hold the scan at its own density.
    if (e->childMask) {
      EXPECT_GT(n.pointSpacing, 0.9 * n.spacing) << n.key.name();
    }
  }
  EXPECT_GT(measured, s.drawList().size() / 2);
}

// Rewrites an octree as format version 1 wrote it: byte 3 of every hierarchy entry 0, the root
// chunk's checksum recomputed, "version": 1. Only for octrees whose hierarchy is one chunk.
void downgradeToVersion1(const fs::path& dir) {
  std::ifstream in(dir / "hierarchy.bin", std::ios::binary);
  std::vector<uint8_t> h((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  for (size_t i = 0; i + 32 <= h.size(); i += 32) {
    ASSERT_NE(h[i], uint8_t(NodeType::Proxy)) << "the test octree must be one hierarchy chunk";
    h[i + 3] = 0;
  }
  std::ofstream(dir / "hierarchy.bin", std::ios::binary)
      .write(reinterpret_cast<const char*>(h.data()), h.size());
  std::ifstream mf(dir / "metadata.json");
  std::stringstream ss;
  ss << mf.rdbuf();
  std::string meta = ss.str();
  meta = std::regex_replace(meta, std::regex(R"("version":\s*2\b)"), "\"version\": 1");
  meta = std::regex_replace(
      meta, std::regex(R"("root_chunk_checksum":\s*\d+)"),
      "\"root_chunk_checksum\": " + std::to_string(checksum64(h.data(), h.size())));
  std::ofstream(dir / "metadata.json") << meta;
}

TEST(MeasuredSpacing, Version1OctreesOpenWithTheNominalSpacing) {
  test::TempDir tmp;
  test::buildSyntheticOctree(tmp.path() / "o", surfaces(30'000), 5000);
  downgradeToVersion1(tmp.path() / "o");
  OctreeReader reader(tmp.path() / "o");
  EXPECT_EQ(reader.metadata().version, 1);
  MemoryStore store(reader.metadata());
  Streamer s(reader, store, generous());
  const Metadata& m = reader.metadata();
  const glm::dvec3 c = test::boundsCenter(m);
  const double size = m.bounds.max.x - m.bounds.min.x;
  ASSERT_GT(test::runUntilComplete(s, test::camera(c + glm::dvec3(size, size, size), c), 5000), 0);
  ASSERT_FALSE(s.drawList().empty());
  for (const DrawNode& n : s.drawList()) EXPECT_EQ(n.pointSpacing, n.spacing) << n.key.name();
}
