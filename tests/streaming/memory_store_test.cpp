// The memory store: its 16-byte points decode to the scan's positions and colours, and its
// bookkeeping catches leaks and double releases.
#include "nestlight/streaming/memory_store.h"

#include <gtest/gtest.h>

#include <cstring>

#include "nestlight/octree/octree_reader.h"
#include "streaming_support.h"
#include "test_support.h"

using namespace nestlight;
using namespace nestlight::streaming;

TEST(MemoryStore, PointsAreNodeRelativeFloatsAndRgba8) {
  test::TempDir t;
  SyntheticSpec spec;
  spec.points = 20000;
  spec.origin = {500000, 5000000, 100};
  test::buildSyntheticOctree(t.path() / "o", spec);
  OctreeReader reader(t.path() / "o");
  const Metadata& m = reader.metadata();
  const int rgb = m.layout.find("rgb");
  ASSERT_GE(rgb, 0);
  MemoryStore store(m);
  for (auto& [k, e] : reader.allNodes()) {
    PointBuffer pts = reader.readNode(k);
    PointBuffer copy = pts;
    PreparedNode p;
    store.prepare(k, std::move(pts), p);
    ASSERT_EQ(p.numPoints, e.numPoints);
    ASSERT_EQ(p.bytes.size(), size_t(e.numPoints) * MemoryStore::kBytesPerPoint);
    const Box3d cube = m.nodeBounds(k.level, k.x, k.y, k.z);
    for (size_t i = 0; i < copy.size(); ++i) {
      float xyz[3];
      uint8_t rgba[4];
      std::memcpy(xyz, &p.bytes[i * 16], 12);
      std::memcpy(rgba, &p.bytes[i * 16 + 12], 4);
      for (int a = 0; a < 3; ++a) {
        const double world = m.world(a, copy.pos[3 * i + a]);
        EXPECT_NEAR(cube.min[a] + xyz[a], world, 1e-3 * 0.5 + 1e-6 * (cube.max[a] - cube.min[a]));
      }
      uint16_t c[3];
      std::memcpy(c, copy.attrsOf(i) + m.layout.offset(size_t(rgb)), 6);
      for (int a = 0; a < 3; ++a) EXPECT_EQ(rgba[a], c[a] >> 8);
      EXPECT_EQ(rgba[3], 255);
    }
  }
}

TEST(MemoryStore, CountsHandlesBytesAndBadReleases) {
  Metadata m;
  MemoryStore store(m);
  PreparedNode a, b;
  a.key = NodeKey::root();
  a.bytes.assign(160, 1);
  b.key = NodeKey::root().child(3);
  b.bytes.assign(32, 2);
  const uint64_t ha = store.upload(a), hb = store.upload(b);
  EXPECT_GT(ha, 0u);
  EXPECT_NE(ha, hb);
  EXPECT_EQ(store.liveHandles(), 2u);
  EXPECT_EQ(store.liveBytes(), 192u);
  EXPECT_EQ(store.keyOf(hb), b.key);
  EXPECT_EQ(store.bytesOf(ha), a.bytes);
  store.release(ha);
  EXPECT_EQ(store.liveBytes(), 32u);
  EXPECT_EQ(store.maxLiveBytes(), 192u);
  store.release(ha);   // twice
  store.release(999);  // never uploaded
  EXPECT_EQ(store.badReleases(), 2u);
  store.release(hb);
  EXPECT_EQ(store.liveHandles(), 0u);
  EXPECT_EQ(store.uploads(), 2u);
  EXPECT_EQ(store.releases(), 2u);
}
