// The scheduler: the complete cut equals the ideal one, budgets hold at every frame, nothing is
// drawn without its ancestors, every request ends, faults are reported once and rendering goes
// on, destruction leaks nothing, and the render thread reads no file.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <mutex>
#include <random>

#include "nestlight/octree/error.h"
#include "streaming_support.h"
#include "test_support.h"

using namespace nestlight;
using namespace nestlight::streaming;
using nestlight::test::TempDir;
namespace fs = std::filesystem;

namespace {

// One small octree for the tests that only read it: 200k points, nodes of at most 1000 points,
// so the hierarchy spans several chunks.
class StreamerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    tmp_ = new TempDir();
    SyntheticSpec spec;
    spec.points = 200000;
    spec.seed = 7;
    test::buildSyntheticOctree(tmp_->path() / "o", spec);
  }
  static void TearDownTestSuite() {
    delete tmp_;
    tmp_ = nullptr;
  }
  static fs::path dir() { return tmp_->path() / "o"; }
  static TempDir* tmp_;
};
TempDir* StreamerTest::tmp_ = nullptr;

Budgets smallBudgets() {
  Budgets b;
  b.points = 60000;
  b.gpuBytes = 600 * 1024;
  b.uploadBytesPerFrame = 128 * 1024;
  b.loaderThreads = 2;
  b.spacingPixels = 1.0;
  return b;
}

// A random view of the scan: eyes around and inside it, looking at a random point of it.
View randomView(std::mt19937& rng, const Metadata& m) {
  std::uniform_real_distribution<double> u(0, 1);
  const glm::dvec3 lo(m.bounds.min.x, m.bounds.min.y, m.bounds.min.z);
  const glm::dvec3 hi(m.bounds.max.x, m.bounds.max.y, m.bounds.max.z);
  const glm::dvec3 target = lo + (hi - lo) * glm::dvec3(u(rng), u(rng), u(rng));
  const double diag = glm::length(hi - lo);
  glm::dvec3 eye = test::boundsCenter(m) + glm::dvec3(u(rng) - 0.5, u(rng) - 0.5, 0.1 + u(rng)) *
                                               diag * (0.2 + 1.5 * u(rng));
  if (glm::length(eye - target) < 1e-3) eye.z += 1;
  return test::camera(eye, target);
}

TEST_F(StreamerTest, CompleteCutEqualsIdealCutAfterCameraStops) {
  OctreeReader reader(dir());
  const Metadata& m = reader.metadata();
  const glm::dvec3 c = test::boundsCenter(m);
  struct Case {
    View view;
    Budgets budgets;
  };
  Budgets generous = smallBudgets();
  generous.points = 10'000'000;
  generous.gpuBytes = 1ull << 30;
  Budgets pointBound = smallBudgets();  // the point budget ends the cut
  Budgets byteBound = generous;         // the byte budget ends the cut
  byteBound.gpuBytes = 300 * 1024;
  std::vector<Case> cases = {
      {test::camera(c + glm::dvec3(0, -150, 80), c), generous},
      {test::camera(c + glm::dvec3(10, -20, 5), c + glm::dvec3(0, 10, 0)), generous},
      {test::camera(c + glm::dvec3(0, 0, 3), c + glm::dvec3(30, 0, 0)), pointBound},
      {test::camera(c + glm::dvec3(-60, -60, 40), c), byteBound},
      {test::camera(c + glm::dvec3(0, -400, 300), c), generous},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE("case " + std::to_string(i));
    MemoryStore store(m);
    Streamer s(reader, store, cases[i].budgets);
    const int frames = test::runUntilComplete(
        s, cases[i].view, 5000, [&] { test::expectFrameInvariants(s, store, cases[i].budgets); });
    ASSERT_GT(frames, 0) << "cut not complete";
    const auto ideal =
        test::idealCut(reader, cases[i].view, cases[i].budgets, MemoryStore::kBytesPerPoint);
    EXPECT_FALSE(ideal.empty());
    EXPECT_EQ(test::drawKeys(s), test::sorted(ideal));
    EXPECT_EQ(s.stats().cutNodes, ideal.size());
    // A complete cut stays complete and unchanged while the camera stays.
    for (int f = 0; f < 5; ++f) EXPECT_TRUE(s.update(cases[i].view).complete);
    EXPECT_EQ(test::drawKeys(s), test::sorted(ideal));
  }
}

TEST_F(StreamerTest, FrustumCullingKeepsOnlyVisibleNodes) {
  OctreeReader reader(dir());
  const Metadata& m = reader.metadata();
  const glm::dvec3 c = test::boundsCenter(m);
  MemoryStore store(m);
  Budgets b = smallBudgets();
  b.points = 10'000'000;
  b.gpuBytes = 1ull << 30;
  Streamer s(reader, store, b);
  // Looking away from the scan: nothing to draw, and nothing pending.
  const View away = test::camera(c + glm::dvec3(0, -200, 10), c + glm::dvec3(0, -400, 10));
  ASSERT_GT(test::runUntilComplete(s, away, 100), 0);
  EXPECT_EQ(s.stats().cutNodes, 0u);
  EXPECT_TRUE(s.drawList().empty());
  // A narrow view of one corner: every drawn node's cube meets the frustum (checked on corner
  // points in clip space), and some nodes of the scan are left out.
  const View corner =
      test::camera(c + glm::dvec3(-30, -30, 20), glm::dvec3(m.bounds.min.x, m.bounds.min.y, 0));
  ASSERT_GT(test::runUntilComplete(s, corner, 5000), 0);
  uint64_t drawn = 0;
  for (const auto& d : s.drawList()) {
    const Box3d& bx = d.worldBounds;
    bool allOutsideOnePlane = false;
    for (int axis = 0; axis < 3 && !allOutsideOnePlane; ++axis)
      for (int sign = -1; sign <= 1 && !allOutsideOnePlane; sign += 2) {
        bool all = true;
        for (int k = 0; k < 8 && all; ++k) {
          glm::dvec4 p((k & 4) ? bx.max.x : bx.min.x, (k & 2) ? bx.max.y : bx.min.y,
                       (k & 1) ? bx.max.z : bx.min.z, 1.0);
          glm::dvec4 q = corner.clipFromWorld * p;
          all = sign * q[axis] > q.w;
        }
        allOutsideOnePlane = all;
      }
    EXPECT_FALSE(allOutsideOnePlane) << d.key.name();
    drawn += d.numPoints;
  }
  EXPECT_GT(drawn, 0u);
  EXPECT_LT(s.stats().cutNodes, m.nodes);
}

TEST_F(StreamerTest, InvariantsHoldOnRandomFastFlight) {
  OctreeReader reader(dir());
  const Metadata& m = reader.metadata();
  MemoryStore store(m);
  const Budgets b = smallBudgets();
  Streamer s(reader, store, b);
  std::mt19937 rng(3);
  View v = randomView(rng, m);
  // At least 600 frames, and on until the small budget forced evictions and teleports made
  // requests stale (a slow machine loads less per frame).
  for (int f = 0; f < 600 || ((s.totals().evicted == 0 || s.totals().cancelled == 0) && f < 20000);
       ++f) {
    if (f % 3 == 0) v = randomView(rng, m);  // a teleport every third frame
    s.update(v);
    test::expectFrameInvariants(s, store, b);
    if (HasFailure()) break;
    std::this_thread::sleep_for(std::chrono::microseconds(300));  // the loaders keep up, partly
  }
  // The store saw every upload: the budget held at every moment, not only between frames.
  EXPECT_LE(store.maxLiveBytes(), b.gpuBytes);
  EXPECT_LE(s.totals().maxResidentBytes, b.gpuBytes);
  EXPECT_GT(s.totals().evicted, 0u);
  EXPECT_GT(s.totals().cancelled, 0u);
}

TEST_F(StreamerTest, EveryRequestEndsCompletedOrCancelled) {
  OctreeReader reader(dir());
  const Metadata& m = reader.metadata();
  MemoryStore store(m);
  Streamer s(reader, store, smallBudgets());
  std::mt19937 rng(11);
  View v = randomView(rng, m);
  for (int f = 0; f < 300; ++f) {
    v = randomView(rng, m);
    s.update(v);
    std::this_thread::sleep_for(std::chrono::microseconds(300));
  }
  ASSERT_GT(test::runUntilComplete(s, v, 5000), 0);
  ASSERT_TRUE(test::drain(s, v));
  const Streamer::Totals t = s.totals();
  EXPECT_GT(t.requested, 0u);
  EXPECT_EQ(t.requested, t.completed + t.cancelled + t.failed);
  EXPECT_EQ(t.failed, 0u);
  EXPECT_GE(t.completed, t.uploaded);
}

TEST_F(StreamerTest, UpdateNeverReadsAFile) {
  OctreeReader reader(dir());
  const Metadata& m = reader.metadata();
  MemoryStore store(m);
  Streamer s(reader, store, smallBudgets());
  std::mt19937 rng(5);
  const uint64_t calls = OctreeReader::threadReadCalls(), bytes = OctreeReader::threadBytesRead();
  const uint64_t hierarchyBefore = reader.hierarchyBytesRead();
  for (int f = 0; f < 400; ++f) {
    s.update(randomView(rng, m));
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  EXPECT_EQ(OctreeReader::threadReadCalls(), calls);
  EXPECT_EQ(OctreeReader::threadBytesRead(), bytes);
  // ... while the loaders did read, hierarchy chunks included.
  EXPECT_GT(s.totals().bytesRead, 0u);
  EXPECT_GT(reader.hierarchyBytesRead(), hierarchyBefore);
  EXPECT_GT(reader.payloadBytesRead(), 0u);
}

TEST_F(StreamerTest, UploadCapStillLetsOneNodeThroughPerFrame) {
  OctreeReader reader(dir());
  const Metadata& m = reader.metadata();
  MemoryStore store(m);
  Budgets b = smallBudgets();
  b.uploadBytesPerFrame = 1;  // smaller than any node
  Streamer s(reader, store, b);
  const View v =
      test::camera(test::boundsCenter(m) + glm::dvec3(0, -120, 60), test::boundsCenter(m));
  const int frames = test::runUntilComplete(s, v, 5000, [&] { EXPECT_LE(s.stats().uploads, 1u); });
  ASSERT_GT(frames, 0);
  EXPECT_GE(uint32_t(frames), s.stats().cutNodes);
  EXPECT_EQ(test::drawKeys(s),
            test::sorted(test::idealCut(reader, v, b, MemoryStore::kBytesPerPoint)));
}

TEST_F(StreamerTest, BudgetsChangedAtRuntimeTakeEffect) {
  OctreeReader reader(dir());
  const Metadata& m = reader.metadata();
  const glm::dvec3 c = test::boundsCenter(m);
  const View v = test::camera(c + glm::dvec3(0, -100, 50), c);
  MemoryStore store(m);
  Budgets b = smallBudgets();
  b.points = 150000;
  b.gpuBytes = 4u << 20;
  Streamer s(reader, store, b);
  ASSERT_GT(test::runUntilComplete(s, v, 5000), 0);
  const uint64_t points = s.stats().cutPoints, bytes = s.stats().residentBytes;
  ASSERT_GT(points, 20000u);

  // A smaller point budget: the next frame's cut and draw list obey it.
  Budgets fewer = b;
  fewer.points = points / 4;
  s.setBudgets(fewer);
  EXPECT_EQ(s.budgets().points, points / 4);
  s.update(v);
  EXPECT_LE(s.stats().cutPoints, fewer.points);
  EXPECT_LE(s.stats().drawPoints, fewer.points);
  EXPECT_GT(s.stats().drawPoints, 0u);

  // A smaller GPU budget than what is resident: evicted within the next update, before any
  // upload, and the cut shrinks to fit.
  Budgets less = b;
  less.gpuBytes = bytes / 3;
  less.loaderThreads = 1;
  s.setBudgets(less);
  const uint64_t uploadsBefore = store.uploads();
  s.update(v);
  EXPECT_LE(s.stats().residentBytes, less.gpuBytes);
  EXPECT_LE(store.liveBytes(), less.gpuBytes);
  ASSERT_GT(
      test::runUntilComplete(s, v, 5000, [&] { test::expectFrameInvariants(s, store, less); }), 0);
  EXPECT_EQ(test::drawKeys(s),
            test::sorted(test::idealCut(reader, v, less, MemoryStore::kBytesPerPoint)));
  EXPECT_GE(store.uploads(), uploadsBefore);

  // Larger budgets and more loaders: more detail, up to the new ideal cut.
  Budgets more = b;
  more.points = 1'000'000;
  more.gpuBytes = 64u << 20;
  more.loaderThreads = 3;
  more.spacingPixels = 0.3;
  s.setBudgets(more);
  ASSERT_GT(test::runUntilComplete(s, v, 5000), 0);
  EXPECT_GT(s.stats().cutPoints, points);
  EXPECT_EQ(test::drawKeys(s),
            test::sorted(test::idealCut(reader, v, more, MemoryStore::kBytesPerPoint)));
}

TEST_F(StreamerTest, DestructionMidLoadLeaksNothing) {
  OctreeReader reader(dir());
  const Metadata& m = reader.metadata();
  const glm::dvec3 c = test::boundsCenter(m);
  for (int round = 0; round < 12; ++round) {
    MemoryStore store(m);
    {
      Budgets b = smallBudgets();
      b.points = 10'000'000;
      b.gpuBytes = 1ull << 30;
      b.loaderThreads = 1 + round % 3;
      Streamer s(reader, store, b);
      for (int f = 0; f < round; ++f) {
        s.update(test::camera(c + glm::dvec3(f * 7.0, -50, 20), c));
        std::this_thread::sleep_for(std::chrono::microseconds(300));
      }
      if (round > 2) {
        EXPECT_GT(s.stats().queueLength + s.stats().inFlight + s.stats().readyWaiting, 0u);
      }
    }
    EXPECT_EQ(store.liveHandles(), 0u);
    EXPECT_EQ(store.liveBytes(), 0u);
    EXPECT_EQ(store.uploads(), store.releases());
    EXPECT_EQ(store.badReleases(), 0u);
  }
}

TEST_F(StreamerTest, DefaultBadNodeLogIsOneLineOnStderr) {
  TempDir t;
  fs::copy(dir(), t.path() / "o");
  OctreeReader probe(t.path() / "o");
  const auto root = *probe.node(NodeKey::root());
  // Damage the root's payload: one line on stderr, nothing drawn, frames go on.
  {
    int fd = ::open((t.path() / "o" / "octree.bin").c_str(), O_RDWR);
    ASSERT_GE(fd, 0);
    uint8_t byte = 0;
    ASSERT_EQ(::pread(fd, &byte, 1, off_t(root.byteOffset + root.byteSize / 2)), 1);
    byte ^= 0xFF;
    ASSERT_EQ(::pwrite(fd, &byte, 1, off_t(root.byteOffset + root.byteSize / 2)), 1);
    ::close(fd);
  }
  OctreeReader reader(t.path() / "o");
  MemoryStore store(reader.metadata());
  testing::internal::CaptureStderr();
  {
    Streamer s(reader, store, smallBudgets());
    const glm::dvec3 c = test::boundsCenter(reader.metadata());
    for (int f = 0; f < 300 && s.stats().badNodes == 0; ++f) {
      s.update(test::camera(c + glm::dvec3(0, -100, 50), c));
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    for (int f = 0; f < 20; ++f) s.update(test::camera(c + glm::dvec3(0, -100, 50), c));
    EXPECT_EQ(s.stats().badNodes, 1u);
    EXPECT_TRUE(s.drawList().empty());
    EXPECT_TRUE(s.stats().complete);  // nothing left it could do
  }
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find("node r:"), std::string::npos) << err;
  EXPECT_NE(err.find("octree.bin"), std::string::npos) << err;
}

struct BadLog {
  std::mutex mutex;
  std::vector<BadNode> nodes;
  void attach(Streamer& s) {
    s.onBadNode([this](const BadNode& b) {
      std::lock_guard<std::mutex> lock(mutex);
      nodes.push_back(b);
    });
  }
  size_t count(const NodeKey& k) {
    std::lock_guard<std::mutex> lock(mutex);
    return size_t(
        std::count_if(nodes.begin(), nodes.end(), [&](const BadNode& b) { return b.key == k; }));
  }
};

void flipByte(const fs::path& file, uint64_t offset) {
  int fd = ::open(file.c_str(), O_RDWR);
  ASSERT_GE(fd, 0);
  uint8_t byte = 0;
  ASSERT_EQ(::pread(fd, &byte, 1, off_t(offset)), 1);
  byte ^= 0x5A;
  ASSERT_EQ(::pwrite(fd, &byte, 1, off_t(offset)), 1);
  ::close(fd);
}

// Whether a drawn node lies below `k` (or is `k`).
bool drawsBelow(const Streamer& s, const NodeKey& k) {
  for (const auto& d : s.drawList())
    if (k.isAncestorOf(d.key)) return true;
  return false;
}

TEST_F(StreamerTest, CorruptedPayloadIsReportedOnceAndRenderingGoesOn) {
  TempDir t;
  fs::copy(dir(), t.path() / "o");
  const glm::dvec3 c = test::boundsCenter(OctreeReader(t.path() / "o").metadata());
  const View v = test::camera(c + glm::dvec3(0, -100, 50), c);
  Budgets b = smallBudgets();
  b.points = 10'000'000;
  b.gpuBytes = 1ull << 30;
  // A level-2 node of the ideal cut that has children in it too.
  NodeKey victim;
  uint64_t offset = 0;
  {
    OctreeReader r(t.path() / "o");
    auto ideal = test::idealCut(r, v, b, MemoryStore::kBytesPerPoint);
    for (const NodeKey& k : ideal) {
      if (k.level != 2) continue;
      auto e = r.node(k);
      if (e->byteSize == 0 || !e->childMask) continue;
      victim = k;
      offset = e->byteOffset + e->byteSize / 2;
      break;
    }
    ASSERT_EQ(victim.level, 2u);
  }
  flipByte(t.path() / "o" / "octree.bin", offset);

  OctreeReader reader(t.path() / "o");
  MemoryStore store(reader.metadata());
  BadLog log;
  Streamer s(reader, store, b);
  log.attach(s);
  ASSERT_GT(test::runUntilComplete(s, v, 5000, [&] { test::expectFrameInvariants(s, store, b); }),
            0);
  // Fly away and back: the node is not asked for again.
  for (int f = 0; f < 50; ++f) s.update(test::camera(c + glm::dvec3(f, -100 + f, 50), c));
  ASSERT_GT(test::runUntilComplete(s, v, 5000), 0);
  EXPECT_EQ(log.count(victim), 1u);
  ASSERT_EQ(s.badNodes().size(), 1u);
  EXPECT_EQ(s.badNodes()[0].key, victim);
  EXPECT_NE(s.badNodes()[0].message.find(victim.name()), std::string::npos);
  EXPECT_NE(s.badNodes()[0].message.find("octree.bin"), std::string::npos);
  EXPECT_EQ(s.stats().badNodes, 1u);
  EXPECT_EQ(s.totals().failed, 1u);
  EXPECT_FALSE(drawsBelow(s, victim));
  EXPECT_GT(s.stats().drawNodes, 10u);  // the rest of the scan is drawn
  // The complete cut is the ideal one without the bad node's subtree.
  std::vector<NodeKey> expected;
  for (const NodeKey& k : test::idealCut(reader, v, b, MemoryStore::kBytesPerPoint))
    if (!victim.isAncestorOf(k)) expected.push_back(k);
  EXPECT_EQ(test::drawKeys(s), test::sorted(expected));
}

TEST_F(StreamerTest, PayloadFileTruncatedWhileViewing) {
  TempDir t;
  fs::copy(dir(), t.path() / "o");
  const fs::path bin = t.path() / "o" / "octree.bin";
  OctreeReader reader(t.path() / "o");
  const Metadata& m = reader.metadata();
  Budgets b = smallBudgets();
  b.points = 10'000'000;
  b.gpuBytes = 1ull << 30;
  MemoryStore store(m);
  BadLog log;
  Streamer s(reader, store, b);
  log.attach(s);
  // One corner first, complete; then the file loses its last third (the builder writes the
  // root last, so a file truncated before opening draws nothing: checked at the end).
  const glm::dvec3 lo(m.bounds.min.x, m.bounds.min.y, 0), hi(m.bounds.max.x, m.bounds.max.y, 0);
  const View a = test::camera(lo + glm::dvec3(-10, -10, 15), lo + glm::dvec3(10, 10, 0));
  ASSERT_GT(test::runUntilComplete(s, a, 5000), 0);
  const uint64_t size = fs::file_size(bin), kept = size * 2 / 3;
  fs::resize_file(bin, kept);
  const View v = test::camera(hi + glm::dvec3(10, 10, 15), hi - glm::dvec3(10, 10, 0));
  ASSERT_GT(test::runUntilComplete(s, v, 5000, [&] { test::expectFrameInvariants(s, store, b); }),
            0);
  for (int f = 0; f < 30; ++f) s.update(v);
  EXPECT_GT(s.badNodes().size(), 0u);
  std::set<NodeKey> bad;
  for (const BadNode& n : s.badNodes()) {
    EXPECT_TRUE(bad.insert(n.key).second) << n.key.name() << " reported twice";
    EXPECT_EQ(log.count(n.key), 1u);
    auto e = reader.node(n.key);
    EXPECT_GT(e->byteOffset + e->byteSize, kept) << n.key.name();
    EXPECT_NE(n.message.find("octree.bin"), std::string::npos) << n.message;
  }
  for (const auto& d : s.drawList()) {
    for (NodeKey k = d.key;; k = k.parent()) {
      EXPECT_FALSE(bad.count(k)) << d.key.name();
      if (k.level == 0) break;
    }
  }
  EXPECT_EQ(s.stats().badNodes, bad.size());
  EXPECT_GT(s.stats().drawNodes, 1u);

  // Opened truncated: the root itself is bad, reported once, frames go on with nothing drawn.
  OctreeReader truncated(t.path() / "o");
  MemoryStore store2(m);
  BadLog log2;
  Streamer s2(truncated, store2, b);
  log2.attach(s2);
  ASSERT_GT(test::runUntilComplete(s2, v, 5000), 0);
  EXPECT_EQ(log2.count(NodeKey::root()), 1u);
  EXPECT_TRUE(s2.drawList().empty());
}

TEST_F(StreamerTest, DamagedHierarchyChunkHidesOnlyItsSubtree) {
  TempDir t;
  fs::copy(dir(), t.path() / "o");
  // A proxy of the root chunk (a node 3 levels down whose own chunk holds its subtree).
  NodeKey proxy;
  HierarchyEntry pe;
  {
    OctreeReader r(t.path() / "o");
    for (auto& [k, e] : r.allNodes())
      (void)k, (void)e;  // warm nothing: only to be sure it is valid
  }
  {
    OctreeReader r(t.path() / "o");
    std::vector<NodeKey> stack{NodeKey::root()};
    while (!stack.empty() && proxy.level == 0) {
      NodeKey k = stack.back();
      stack.pop_back();
      auto e = r.peek(k);
      if (!e) continue;
      if (e->type == NodeType::Proxy) {
        proxy = k;
        pe = *e;
        break;
      }
      for (int i = 0; i < 8; ++i)
        if (e->childMask & (1u << i)) stack.push_back(k.child(i));
    }
    ASSERT_EQ(proxy.level, 3u) << "the test octree should span several hierarchy chunks";
    EXPECT_TRUE(r.hierarchyPending(proxy));
  }
  flipByte(t.path() / "o" / "hierarchy.bin", pe.byteOffset + 8);

  OctreeReader reader(t.path() / "o");
  const Metadata& m = reader.metadata();
  MemoryStore store(m);
  Budgets b = smallBudgets();
  b.points = 10'000'000;
  b.gpuBytes = 1ull << 30;
  b.spacingPixels = 0.2;
  BadLog log;
  Streamer s(reader, store, b);
  log.attach(s);
  // Look at the proxy's cube from close by.
  const Box3d cube = m.nodeBounds(proxy.level, proxy.x, proxy.y, proxy.z);
  const glm::dvec3 pc(0.5 * (cube.min.x + cube.max.x), 0.5 * (cube.min.y + cube.max.y),
                      0.5 * (cube.min.z + cube.max.z));
  const View v = test::camera(pc + glm::dvec3(0, -20, 15), pc);
  ASSERT_GT(test::runUntilComplete(s, v, 5000, [&] { test::expectFrameInvariants(s, store, b); }),
            0);
  for (int f = 0; f < 20; ++f) s.update(v);
  ASSERT_EQ(s.badNodes().size(), 1u);
  EXPECT_EQ(s.badNodes()[0].key, proxy);
  EXPECT_EQ(log.count(proxy), 1u);
  EXPECT_NE(s.badNodes()[0].message.find("hierarchy.bin"), std::string::npos)
      << s.badNodes()[0].message;
  EXPECT_FALSE(drawsBelow(s, proxy));
  EXPECT_GT(s.stats().drawNodes, 5u);
}

TEST(Streamer, NationalGridScan) {
  TempDir t;
  SyntheticSpec spec;
  spec.points = 150000;
  spec.origin = {500000, 5000000, 100};
  spec.seed = 9;
  const Metadata meta = test::buildSyntheticOctree(t.path() / "o", spec);
  OctreeReader reader(t.path() / "o");
  const Metadata& m = reader.metadata();
  EXPECT_GT(m.offset.x, 400000);
  const glm::dvec3 c = test::boundsCenter(m);
  const View v = test::camera(c + glm::dvec3(20, -60, 30), c);
  Budgets b = smallBudgets();
  b.points = 10'000'000;
  b.gpuBytes = 1ull << 30;
  MemoryStore store(m);
  Streamer s(reader, store, b);
  ASSERT_GT(test::runUntilComplete(s, v, 5000, [&] { test::expectFrameInvariants(s, store, b); }),
            0);
  const auto ideal = test::idealCut(reader, v, b, MemoryStore::kBytesPerPoint);
  EXPECT_GT(ideal.size(), 5u);
  EXPECT_EQ(test::drawKeys(s), test::sorted(ideal));
  for (const auto& d : s.drawList()) {
    EXPECT_NEAR(d.worldBounds.min.x, 500000, 2000);
    EXPECT_NEAR(d.worldBounds.min.y, 5000000, 2000);
    EXPECT_NEAR(d.spacing, m.spacing / std::pow(2.0, d.key.level), 1e-12);
    // The store's node-relative floats keep millimetres: positions lie inside the node's cube.
    const auto bytes = store.bytesOf(d.handle);
    ASSERT_EQ(bytes.size(), size_t(d.numPoints) * MemoryStore::kBytesPerPoint);
    const double size = d.worldBounds.max.x - d.worldBounds.min.x;
    for (size_t i = 0; i < d.numPoints; i += 97) {
      float xyz[3];
      std::memcpy(xyz, &bytes[i * MemoryStore::kBytesPerPoint], 12);
      for (float f : xyz) {
        EXPECT_GE(f, 0.0f);
        EXPECT_LE(f, size);
      }
    }
  }
}

}  // namespace
