// The on-disk format: node keys, payload codecs, the paged hierarchy, metadata validation.
#include <gtest/gtest.h>

#include <random>

#include "nestlight/octree/codec.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/hierarchy.h"
#include "nestlight/octree/metadata.h"

using namespace nestlight;

TEST(NodeKey, NamesRoundTrip) {
  NodeKey k = NodeKey::root().child(7).child(0).child(3);
  EXPECT_EQ(k.name(), "r703");
  EXPECT_EQ(*NodeKey::parse("r703"), k);
  EXPECT_EQ(k.parent().parent().parent(), NodeKey::root());
  EXPECT_TRUE(NodeKey::root().child(7).isAncestorOf(k));
  EXPECT_FALSE(NodeKey::root().child(6).isAncestorOf(k));
  EXPECT_FALSE(NodeKey::parse("r9").has_value());
  EXPECT_FALSE(NodeKey::parse("x0").has_value());
}

TEST(NodeKey, BreadthFirstMortonOrder) {
  NodeKey a = NodeKey::root().child(1), b = NodeKey::root().child(4);
  EXPECT_LT(a, b);
  EXPECT_LT(b, a.child(0));  // shallower first
  EXPECT_LT(a.child(7), b.child(0));
}

namespace {
PointLayout testLayout() {
  PointLayout l;
  l.add({"rgb", ScalarType::U16, 3, ""});
  l.add({"intensity", ScalarType::U16, 1, ""});
  l.add({"normal", ScalarType::F32, 3, ""});
  l.add({"gps_time", ScalarType::F64, 1, ""});
  l.add({"classification", ScalarType::U8, 1, ""});
  return l;
}
PointBuffer randomPoints(const PointLayout& l, size_t n, uint32_t extent, unsigned seed) {
  std::mt19937 rng(seed);
  PointBuffer p(l.stride());
  p.pos.resize(3 * n);
  p.attrs.resize(n * l.stride());
  for (auto& v : p.pos) v = rng() % extent;
  for (auto& b : p.attrs) b = static_cast<uint8_t>(rng());
  // Realistic floats (random bytes may hold NaN payloads, which must survive too).
  return p;
}
}  // namespace

class CodecRoundTrip : public ::testing::TestWithParam<Codec> {};

TEST_P(CodecRoundTrip, ExactForEveryType) {
  const PointLayout l = testLayout();
  for (size_t n : {size_t(1), size_t(2), size_t(1000), size_t(20000)}) {
    PointBuffer in = randomPoints(l, n, 1u << 20, static_cast<unsigned>(n));
    std::vector<uint8_t> bytes = encodePayload(GetParam(), l, in);
    PointBuffer out;
    ASSERT_EQ(decodePayload(GetParam(), l, bytes.data(), bytes.size(), n, out), "");
    ASSERT_EQ(out.size(), n);
    if (GetParam() == Codec::Draco) {
      // Draco's kd-tree may reorder points: compare as multisets of records.
      auto records = [&](const PointBuffer& p) {
        std::vector<std::vector<uint8_t>> r(p.size());
        for (size_t i = 0; i < p.size(); ++i) {
          r[i].assign(reinterpret_cast<const uint8_t*>(&p.pos[3 * i]),
                      reinterpret_cast<const uint8_t*>(&p.pos[3 * i]) + 12);
          r[i].insert(r[i].end(), p.attrsOf(i), p.attrsOf(i) + p.stride);
        }
        std::sort(r.begin(), r.end());
        return r;
      };
      EXPECT_EQ(records(in), records(out));
    } else {
      EXPECT_EQ(in.pos, out.pos);
      EXPECT_EQ(in.attrs, out.attrs);
    }
  }
}

TEST_P(CodecRoundTrip, RejectsDamage) {
  const PointLayout l = testLayout();
  PointBuffer in = randomPoints(l, 500, 1000, 7);
  std::vector<uint8_t> bytes = encodePayload(GetParam(), l, in);
  PointBuffer out;
  // Truncated payloads and wrong counts are errors, not crashes.
  EXPECT_NE(decodePayload(GetParam(), l, bytes.data(), bytes.size() / 2, 500, out), "");
  EXPECT_NE(decodePayload(GetParam(), l, bytes.data(), bytes.size(), 501, out), "");
  EXPECT_NE(decodePayload(GetParam(), l, bytes.data(), 0, 500, out), "");
}

INSTANTIATE_TEST_SUITE_P(AllCodecs, CodecRoundTrip,
                         ::testing::Values(Codec::Raw, Codec::Zstd, Codec::Draco),
                         [](const auto& info) { return std::string(codecName(info.param)); });

TEST(Codec, ZstdIsCompactOnSortedSurfaces) {
  // A 2D grid of points with smooth colour, in Morton-like order: the SoA delta codec must do far
  // better than the 18 raw bytes per point of xyz + rgb.
  PointLayout l;
  l.add({"rgb", ScalarType::U16, 3, ""});
  PointBuffer p(l.stride());
  for (uint32_t y = 0; y < 128; ++y)
    for (uint32_t x = 0; x < 128; ++x) {
      uint32_t pos[3] = {x * 10, y * 10, 5000 + (x + y) % 3};
      uint16_t rgb[3] = {uint16_t(x * 257), uint16_t(y * 257), uint16_t(128 * 257)};
      p.push(pos, reinterpret_cast<uint8_t*>(rgb));
    }
  std::vector<uint8_t> bytes = encodePayload(Codec::Zstd, l, p);
  EXPECT_LT(double(bytes.size()) / p.size(), 4.0);
}

TEST(Hierarchy, ChunksRoundTripAndRootChunkIsSmall) {
  // A full tree of depth 5: 1 + 8 + ... + 8^5 nodes.
  std::vector<NodeRecord> nodes;
  std::function<void(NodeKey)> add = [&](NodeKey k) {
    nodes.push_back({k, Codec::Zstd, k.level * 10 + 1, nodes.size() * 100, 100, nodes.size()});
    if (k.level < 5)
      for (int i = 0; i < 8; ++i) add(k.child(i));
  };
  add(NodeKey::root());
  HierarchyBlob blob = buildHierarchy(nodes);
  EXPECT_LE(blob.rootChunkSize, 64u * 1024);
  EXPECT_EQ(blob.rootChunkSize, (1 + 8 + 64 + 512) * kHierarchyEntryBytes);
  // Walk every chunk the way a reader does.
  std::map<std::string, HierarchyEntry> found;
  std::function<void(NodeKey, uint64_t, uint64_t)> walk = [&](NodeKey root, uint64_t off,
                                                              uint64_t size) {
    std::vector<std::pair<NodeKey, HierarchyEntry>> out;
    ASSERT_EQ(parseHierarchyChunk(blob.bytes.data() + off, size, root, kHierarchyStep, out), "");
    for (auto& [k, e] : out) {
      if (e.type == NodeType::Proxy) {
        if (k == root) continue;
        walk(k, e.byteOffset, e.byteSize);
      } else {
        found[k.name()] = e;
      }
    }
  };
  walk(NodeKey::root(), 0, blob.rootChunkSize);
  ASSERT_EQ(found.size(), nodes.size());
  for (const auto& n : nodes) {
    const HierarchyEntry& e = found.at(n.key.name());
    EXPECT_EQ(e.numPoints, n.numPoints);
    EXPECT_EQ(e.byteOffset, n.byteOffset);
    EXPECT_EQ(e.checksum, n.checksum);
    EXPECT_EQ(e.type, n.key.level == 5 ? NodeType::Leaf : NodeType::Inner);
  }
}

TEST(Hierarchy, RejectsInconsistentChunks) {
  std::vector<NodeRecord> nodes = {{NodeKey::root(), Codec::Raw, 1, 0, 10, 0},
                                   {NodeKey::root().child(3), Codec::Raw, 1, 10, 10, 0}};
  HierarchyBlob blob = buildHierarchy(nodes);
  std::vector<std::pair<NodeKey, HierarchyEntry>> out;
  EXPECT_NE(parseHierarchyChunk(blob.bytes.data(), blob.bytes.size() - kHierarchyEntryBytes,
                                NodeKey::root(), 3, out),
            "");
  out.clear();
  std::vector<uint8_t> extra = blob.bytes;
  extra.insert(extra.end(), blob.bytes.begin(), blob.bytes.begin() + kHierarchyEntryBytes);
  EXPECT_NE(parseHierarchyChunk(extra.data(), extra.size(), NodeKey::root(), 3, out), "");
  out.clear();
  EXPECT_NE(parseHierarchyChunk(blob.bytes.data(), 7, NodeKey::root(), 3, out), "");
}

TEST(Metadata, RoundTripAndErrorsNameTheField) {
  Metadata m;
  m.points = 10;
  m.nodes = 1;
  m.cubeSize = 1024;
  m.layout.add({"rgb", ScalarType::U16, 3, ""});
  m.accounting = {12, 10, 1, {{"non_finite_coordinate", 1}}};
  m.bounds.extend(1, 2, 3);
  nlohmann::json j = m.toJson();
  Metadata back = Metadata::fromJson(j, "m.json");
  EXPECT_EQ(back.points, 10u);
  EXPECT_EQ(back.layout, m.layout);
  EXPECT_EQ(back.accounting.rejected.at("non_finite_coordinate"), 1u);
  EXPECT_TRUE(back.accounting.balanced());

  j["cube_size"] = 1000;  // not a power of two
  try {
    Metadata::fromJson(j, "m.json");
    FAIL() << "accepted a bad cube_size";
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), "m.json");
    EXPECT_NE(e.position().find("cube_size"), std::string::npos);
  }
  j = m.toJson();
  j["attributes"][0]["type"] = "quaternion";
  EXPECT_THROW(Metadata::fromJson(j, "m.json"), Error);
  j = m.toJson();
  j.erase("accounting");
  EXPECT_THROW(Metadata::fromJson(j, "m.json"), Error);
}
