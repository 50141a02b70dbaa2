// OctreeReader's non-blocking API for streaming: peek() answers from the chunks already read and
// never reads a file, ensureLoaded() reads chunks on demand (from any thread), a damaged chunk
// fails the same way on every call, and per-thread counters see every read.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <map>
#include <thread>

#include "nestlight/converters/builder.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "test_support.h"

using namespace nestlight;
using nestlight::test::TempDir;
namespace fs = std::filesystem;

namespace {

// 100k points in nodes of at most 500: the hierarchy spans several chunks.
class ReaderPeek : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    tmp_ = new TempDir();
    BuildOptions o;
    o.output = tmp_->path() / "o";
    o.progress = ProgressMode::Quiet;
    o.threads = 2;
    o.maxNodePoints = 500;
    SyntheticSpec spec;
    spec.points = 100000;
    std::vector<std::unique_ptr<PointReader>> r;
    r.push_back(openSynthetic(spec));
    buildOctree(std::move(r), o);
  }
  static void TearDownTestSuite() {
    delete tmp_;
    tmp_ = nullptr;
  }
  static fs::path dir() { return tmp_->path() / "o"; }
  static TempDir* tmp_;

  // A proxy of the root chunk.
  static NodeKey firstProxy(const OctreeReader& r) {
    std::vector<NodeKey> stack{NodeKey::root()};
    while (!stack.empty()) {
      NodeKey k = stack.back();
      stack.pop_back();
      auto e = r.peek(k);
      if (!e) continue;
      if (e->type == NodeType::Proxy) return k;
      for (int i = 0; i < 8; ++i)
        if (e->childMask & (1u << i)) stack.push_back(k.child(i));
    }
    return NodeKey::root();
  }
};
TempDir* ReaderPeek::tmp_ = nullptr;

TEST_F(ReaderPeek, PeekAnswersFromLoadedChunksWithoutReading) {
  OctreeReader r(dir());
  const NodeKey proxy = firstProxy(r);
  ASSERT_EQ(proxy.level, 3u);
  const uint64_t calls = OctreeReader::threadReadCalls(), bytes = OctreeReader::threadBytesRead();
  const uint64_t hierarchy = r.hierarchyBytesRead();

  EXPECT_TRUE(r.peek(NodeKey::root()).has_value());
  auto p = r.peek(proxy);
  ASSERT_TRUE(p.has_value());
  EXPECT_EQ(p->type, NodeType::Proxy);
  EXPECT_NE(p->childMask, 0);
  EXPECT_TRUE(r.hierarchyPending(proxy));
  EXPECT_FALSE(r.hierarchyPending(NodeKey::root()));
  int child = 0;
  while (!(p->childMask & (1u << child))) ++child;
  EXPECT_FALSE(r.peek(proxy.child(child)).has_value());  // below an unread chunk
  EXPECT_TRUE(r.hierarchyPending(proxy.child(child)));
  EXPECT_FALSE(r.peek(NodeKey{1, 5, 5, 5}).has_value());  // out of range: absent

  EXPECT_EQ(OctreeReader::threadReadCalls(), calls);
  EXPECT_EQ(OctreeReader::threadBytesRead(), bytes);
  EXPECT_EQ(r.hierarchyBytesRead(), hierarchy);

  // ensureLoaded reads the proxy's chunk: the proxy's real entry and its children appear.
  auto e = r.ensureLoaded(proxy);
  ASSERT_TRUE(e.has_value());
  EXPECT_NE(e->type, NodeType::Proxy);
  EXPECT_EQ(e->childMask, p->childMask);
  EXPECT_EQ(e->numPoints, p->numPoints);
  EXPECT_GT(r.hierarchyBytesRead(), hierarchy);
  EXPECT_EQ(OctreeReader::threadReadCalls(), calls + 1);
  EXPECT_EQ(OctreeReader::threadBytesRead() - bytes, r.hierarchyBytesRead() - hierarchy);
  EXPECT_FALSE(r.hierarchyPending(proxy));
  auto c = r.peek(proxy.child(child));
  ASSERT_TRUE(c.has_value());
  EXPECT_EQ(r.node(proxy.child(child))->numPoints, c->numPoints);

  // Payload reads are counted too.
  const uint64_t before = OctreeReader::threadBytesRead();
  PointBuffer pts = r.readNode(NodeKey::root());
  EXPECT_EQ(OctreeReader::threadBytesRead() - before, r.node(NodeKey::root())->byteSize);
  EXPECT_EQ(r.payloadBytesRead(), r.node(NodeKey::root())->byteSize);
}

TEST_F(ReaderPeek, ConcurrentEnsureLoadedReadsEachChunkOnce) {
  OctreeReader reference(dir());
  std::map<NodeKey, uint64_t> expected;
  for (auto& [k, e] : reference.allNodes()) expected[k] = e.checksum;
  const uint64_t allHierarchy = reference.hierarchyBytesRead();

  OctreeReader r(dir());
  std::vector<NodeKey> keys;
  for (auto& [k, v] : expected) keys.push_back(k);
  std::atomic<int> failures{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      // Each thread walks the keys in its own order, so threads meet on the same chunks.
      for (size_t i = 0; i < keys.size(); ++i) {
        const NodeKey& k = keys[(i * 7 + size_t(t) * 13) % keys.size()];
        auto e = r.ensureLoaded(k);
        if (!e || e->type == NodeType::Proxy || e->checksum != expected.at(k)) ++failures;
      }
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(failures.load(), 0);
  EXPECT_EQ(r.hierarchyBytesRead(), allHierarchy);  // no chunk read twice
}

TEST_F(ReaderPeek, DamagedChunkFailsTheSameWayEveryTime) {
  TempDir t;
  fs::copy(dir(), t.path() / "o");
  NodeKey proxy;
  HierarchyEntry pe;
  {
    OctreeReader r(t.path() / "o");
    proxy = firstProxy(r);
    pe = *r.peek(proxy);
  }
  {
    int fd = ::open((t.path() / "o" / "hierarchy.bin").c_str(), O_RDWR);
    ASSERT_GE(fd, 0);
    uint8_t b = 0;
    ASSERT_EQ(::pread(fd, &b, 1, off_t(pe.byteOffset + 4)), 1);
    b ^= 1;
    ASSERT_EQ(::pwrite(fd, &b, 1, off_t(pe.byteOffset + 4)), 1);
    ::close(fd);
  }
  OctreeReader r(t.path() / "o");
  Error first = test::errorOf([&] { r.ensureLoaded(proxy); });
  EXPECT_NE(first.file().find("hierarchy.bin"), std::string::npos);
  EXPECT_NE(std::string(first.what()).find("checksum"), std::string::npos) << first.what();
  Error again = test::errorOf([&] { r.readNode(proxy); });
  EXPECT_EQ(std::string(again.what()), std::string(first.what()));
  // Nodes outside the damaged chunk still read.
  EXPECT_NO_THROW(r.readNode(NodeKey::root()));
  EXPECT_TRUE(r.hierarchyPending(proxy));
}

}  // namespace
