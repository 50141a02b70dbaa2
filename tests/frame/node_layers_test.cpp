// Node layers: a GI method's per-node data travels with the node (built on loader threads,
// uploaded as its own buffer, freed with the node) and counts in the byte budget, under a camera
// that flies over a streamed octree with small budgets.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <random>
#include <thread>

#include "nestlight/frame/gl_node_store.h"
#include "nestlight/gl/context.h"
#include "nestlight/octree/rgb9e5.h"
#include "streaming/streaming_support.h"
#include "test_support.h"

namespace nestlight::frame {
namespace {

// A layer of 8 bytes per point (twice the points' float luminance, say), and which thread built it.
class TestLayer : public NodeLayer {
 public:
  std::string name() const override { return "test"; }
  void prepare(const NodeKey&, const PointBuffer& points, const std::vector<uint8_t>& gpu,
               std::vector<uint8_t>& out) const override {
    EXPECT_EQ(gpu.size(), points.size() * kGpuPointBytes);
    out.assign(points.size() * 8, 0x5a);
    if (std::this_thread::get_id() == renderThread) ++onRenderThread;
    ++prepared;
  }
  std::thread::id renderThread = std::this_thread::get_id();
  mutable std::atomic<int> prepared{0}, onRenderThread{0};
};

TEST(NodeLayers, FreedWithTheirNodeAndCountedInTheBudget) {
  test::TempDir t;
  SyntheticSpec spec;
  spec.points = 300'000;
  spec.seed = 9;
  const Metadata meta = test::buildSyntheticOctree(t.path() / "o", spec, 2000);
  OctreeReader reader(t.path() / "o");
  auto ctx = gl::createHeadlessContext();
  auto layer = std::make_shared<TestLayer>();
  GlNodeStore store(reader.metadata(), ColourMode::Rgb);
  EXPECT_EQ(store.addLayer(layer), 1u);
  streaming::Budgets b;
  b.points = 60'000;
  b.gpuBytes = 1u << 20;  // 1 MiB: points (20 B) and the layer (8 B) of about 37k points
  b.uploadBytesPerFrame = 256u << 10;
  {
    streaming::Streamer s(reader, store, b);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1, 1);
    const glm::dvec3 c = test::boundsCenter(meta);
    const double r =
        std::hypot(meta.bounds.max.x - meta.bounds.min.x, meta.bounds.max.y - meta.bounds.min.y,
                   meta.bounds.max.z - meta.bounds.min.z);
    uint64_t maxResident = 0;
    for (int f = 0; f < 400; ++f) {
      // Teleports every 40 frames, drifting in between: nodes keep loading and being evicted.
      static glm::dvec3 eye;
      if (f % 40 == 0) eye = c + glm::dvec3(u(rng), u(rng), 0.3 + 0.5 * std::abs(u(rng))) * r;
      eye += glm::dvec3(0.01 * r, 0, 0);
      const auto& st = s.update(test::camera(eye, c, 320, 240));
      ASSERT_LE(st.residentBytes, b.gpuBytes) << "frame " << f;
      // The streamer's count is the store's: points and layer of every resident node.
      ASSERT_EQ(st.residentBytes, store.liveBytes()) << "frame " << f;
      ASSERT_EQ(store.liveBuffers(), 2 * store.liveNodes()) << "frame " << f;
      for (const auto& n : s.drawList()) {
        ASSERT_NE(store.layerBuffer(n.handle, 1), 0u);
        ASSERT_EQ(store.layerBytes(n.handle, 1), size_t(n.numPoints) * 8);
        ASSERT_EQ(store.layerBytes(n.handle, 0), size_t(n.numPoints) * kGpuPointBytes);
      }
      maxResident = std::max(maxResident, st.residentBytes);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    EXPECT_GT(s.totals().evicted, 10u);
    EXPECT_GT(maxResident, b.gpuBytes / 2);
  }
  EXPECT_EQ(store.liveNodes(), 0u);
  EXPECT_EQ(store.liveBuffers(), 0u);
  EXPECT_EQ(store.liveBytes(), 0u);
  EXPECT_GT(layer->prepared.load(), 20);
  EXPECT_EQ(layer->onRenderThread.load(), 0) << "layers are built by loader threads";
}

TEST(NodeLayers, AtMostThreeBesideThePoints) {
  test::TempDir t;
  SyntheticSpec spec;
  spec.points = 1000;
  const Metadata meta = test::buildSyntheticOctree(t.path() / "o", spec);
  GlNodeStore store(meta, ColourMode::Elevation);
  for (int i = 0; i < NL_MAX_NODE_LAYERS - 1; ++i) store.addLayer(std::make_shared<TestLayer>());
  EXPECT_THROW(store.addLayer(std::make_shared<TestLayer>()), Error);
}

// ColourMode::Hdr: each point's colour word is its layer colour as RGB9E5, point for point in the
// node's order. The colour changes from point to point and node to node over 1e-3 to 6e4 (beyond
// 8 bits and half of half-float range), so a mixed-up order or a wrong scale shows. Tolerance:
// RGB9E5 rounds each channel to half a step, the step being 2^-9 of the power of two above the
// largest channel (so at most the largest / 512), after the layer's half floats (2^-11).
TEST(GlNodeStoreHdr, ColourWordsAreTheLayersColourPointForPoint) {
  test::TempDir t;
  SyntheticSpec spec;
  spec.points = 30'000;
  spec.seed = 4;
  test::buildSyntheticOctree(t.path() / "o", spec, 2000);
  auto colourOf = [](const NodeKey& k, size_t i) {
    const float v = float(std::pow(
        10.0,
        std::fmod(double(k.x * 5 + k.y * 3 + k.z + k.level * 7) + 0.13 * double(i % 61), 7.7) -
            3.0));
    return std::array<float, 3>{v, 0.5f * v, 0.125f * v};
  };
  {
    const auto before = availableColourModes(OctreeReader(t.path() / "o").metadata());
    EXPECT_EQ(std::find(before.begin(), before.end(), ColourMode::Hdr), before.end());
  }
  test::writeColourLayer(t.path() / "o", "hdr", colourOf, 1.0);
  OctreeReader reader(t.path() / "o");
  const auto modes = availableColourModes(reader.metadata());
  EXPECT_NE(std::find(modes.begin(), modes.end(), ColourMode::Hdr), modes.end());
  EXPECT_EQ(parseColourMode("hdr"), ColourMode::Hdr);
  auto layer = std::make_shared<const ColourLayerReader>(t.path() / "o", reader.metadata(), "hdr");
  GlNodeStore store(reader.metadata(), ColourMode::Hdr, layer);
  EXPECT_TRUE(store.hdrColour());
  uint64_t checked = 0;
  for (const auto& [key, e] : reader.allNodes()) {
    streaming::PreparedNode out;
    store.prepare(key, reader.readNode(key), out);
    ASSERT_EQ(out.numPoints, e.numPoints);
    for (size_t i = 0; i < e.numPoints; ++i) {
      uint32_t word;
      std::memcpy(&word, &out.bytes[i * kGpuPointBytes + 12], 4);
      float got[3];
      unpackRgb9e5(word, got);
      // The layer holds half floats: 2^-11 relative, then RGB9E5's step.
      const auto want = colourOf(key, i);
      for (int c = 0; c < 3; ++c)
        ASSERT_NEAR(got[c], want[c], want[0] / 512.0f + want[c] / 2048.0f)
            << key.name() << " point " << i;
      ++checked;
    }
  }
  EXPECT_EQ(checked, reader.metadata().points);
  EXPECT_GT(checked, 20'000u);
}

}  // namespace
}  // namespace nestlight::frame
