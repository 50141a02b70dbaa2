// Node layers: a GI method's per-node data travels with the node (built on loader threads,
// uploaded as its own buffer, freed with the node) and counts in the byte budget, under a camera
// that flies over a streamed octree with small budgets.
#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <random>
#include <thread>

#include "nestlight/frame/gl_node_store.h"
#include "nestlight/gl/context.h"
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
    const double r = std::hypot(meta.bounds.max.x - meta.bounds.min.x, meta.bounds.max.y - meta.bounds.min.y,
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

}  // namespace
}  // namespace nestlight::frame
