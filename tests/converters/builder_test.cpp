// The out-of-core builder: point accounting, hard cases, chunked == in-memory, order independence.
#include "nestlight/converters/builder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>

#include "nestlight/converters/export.h"
#include "nestlight/converters/point_writer.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/converters/verify.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/octree/octree_writer.h"
#include "test_support.h"

using namespace nestlight;
using nestlight::test::TempDir;
namespace fs = std::filesystem;

namespace {

BuildOptions quietOptions(const fs::path& out) {
  BuildOptions o;
  o.output = out;
  o.progress = ProgressMode::Quiet;
  o.threads = 2;
  return o;
}

BuildReport build(const SyntheticSpec& spec, BuildOptions o) {
  std::vector<std::unique_ptr<PointReader>> r;
  r.push_back(openSynthetic(spec));
  return buildOctree(std::move(r), o);
}

// Every stored point as (integer position, attribute bytes), sorted.
using Record = std::vector<uint8_t>;
std::vector<Record> storedRecords(const fs::path& dir) {
  OctreeReader r(dir);
  std::vector<Record> out;
  for (auto& [k, e] : r.allNodes()) {
    PointBuffer p = r.readNode(k);
    for (size_t i = 0; i < p.size(); ++i) {
      Record rec(reinterpret_cast<const uint8_t*>(&p.pos[3 * i]),
                 reinterpret_cast<const uint8_t*>(&p.pos[3 * i]) + 12);
      rec.insert(rec.end(), p.attrsOf(i), p.attrsOf(i) + p.stride);
      out.push_back(std::move(rec));
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The source's points quantised into the octree's grid, as records.
std::vector<Record> sourceRecords(PointReader& src, const Metadata& m) {
  std::vector<Record> out;
  PointBatch b;
  src.rewind();
  const size_t stride = src.header().layout.stride();
  while (src.read(b, 100000)) {
    for (size_t i = 0; i < b.size(); ++i) {
      Record rec(12 + stride);
      for (int a = 0; a < 3; ++a) {
        uint32_t q =
            static_cast<uint32_t>(std::llround((b.xyz[3 * i + a] - m.offset[a]) / m.scale[a]));
        std::memcpy(&rec[4 * a], &q, 4);
      }
      std::memcpy(&rec[12], &b.attrs[i * stride], stride);
      out.push_back(std::move(rec));
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

void expectVerified(const fs::path& dir) {
  VerifyReport v = verifyOctree(dir);
  for (auto& f : v.failures) ADD_FAILURE() << f;
  EXPECT_TRUE(v.ok());
}

}  // namespace

TEST(Builder, EveryPointComesBackExactly) {
  TempDir tmp;
  SyntheticSpec spec;
  spec.points = 300000;
  spec.normals = true;
  BuildReport r = build(spec, quietOptions(tmp.path() / "o"));
  EXPECT_EQ(r.metadata.accounting.input, 300000u);
  EXPECT_EQ(r.metadata.points, 300000u);
  expectVerified(tmp.path() / "o");
  auto src = openSynthetic(spec);
  EXPECT_EQ(storedRecords(tmp.path() / "o"), sourceRecords(*src, r.metadata));
}

TEST(Builder, MillionDuplicatesOfOnePoint) {
  TempDir tmp;
  SyntheticSpec spec;
  spec.shape = SyntheticShape::Duplicates;
  spec.points = 1000000;
  BuildReport r = build(spec, quietOptions(tmp.path() / "keep"));
  EXPECT_EQ(r.metadata.points, 1000000u);
  EXPECT_EQ(r.metadata.accounting.duplicatesMerged, 0u);
  // Coincident points must not drive subdivision: a handful of nodes, not thousands.
  EXPECT_LE(r.metadata.nodes, 64u);
  expectVerified(tmp.path() / "keep");

  BuildOptions o = quietOptions(tmp.path() / "dedup");
  o.dedup = true;
  r = build(spec, o);
  EXPECT_EQ(r.metadata.points, 1u);
  EXPECT_EQ(r.metadata.accounting.duplicatesMerged, 999999u);
  EXPECT_TRUE(r.metadata.accounting.balanced());
  expectVerified(tmp.path() / "dedup");
}

TEST(Builder, SlowFilledCubeOfFiveMillionPointsKeepsNodesSmall) {
  TempDir tmp;
  SyntheticSpec spec;
  spec.shape = SyntheticShape::Cube;
  spec.points = 5000000;
  spec.rgb = false;
  spec.intensity = false;
  BuildOptions o = quietOptions(tmp.path() / "o");
  o.memoryBytes = 256ull << 20;
  BuildReport r = build(spec, o);
  EXPECT_EQ(r.metadata.points, 5000000u);
  OctreeReader reader(tmp.path() / "o");
  for (auto& [k, e] : reader.allNodes()) EXPECT_LE(e.numPoints, o.maxNodePoints) << k.name();
  expectVerified(tmp.path() / "o");
}

TEST(Builder, NationalGridCoordinatesAtMillimetreScale) {
  TempDir tmp;
  SyntheticSpec spec;
  spec.points = 200000;
  spec.origin = {500000.0, 5000000.0, 100.0};
  spec.size = 2000.0;
  spec.precision = 0.001;
  BuildReport r = build(spec, quietOptions(tmp.path() / "o"));
  EXPECT_EQ(r.metadata.scale, (Vec3d{0.001, 0.001, 0.001}));
  expectVerified(tmp.path() / "o");
  // Positions come back to the millimetre: compare world coordinates of every point.
  auto src = openSynthetic(spec);
  EXPECT_EQ(storedRecords(tmp.path() / "o"), sourceRecords(*src, r.metadata));
  ASSERT_EQ(exportOctree(tmp.path() / "o", tmp.file("back.ply")), 200000u);
  auto back = openReader(tmp.file("back.ply"));
  PointBatch a, b;
  src->rewind();
  std::vector<std::array<double, 3>> pa, pb;
  while (src->read(a, 50000))
    for (size_t i = 0; i < a.size(); ++i)
      pa.push_back({a.xyz[3 * i], a.xyz[3 * i + 1], a.xyz[3 * i + 2]});
  while (back->read(b, 50000))
    for (size_t i = 0; i < b.size(); ++i)
      pb.push_back({b.xyz[3 * i], b.xyz[3 * i + 1], b.xyz[3 * i + 2]});
  std::sort(pa.begin(), pa.end());
  std::sort(pb.begin(), pb.end());
  ASSERT_EQ(pa.size(), pb.size());
  double worst = 0;
  for (size_t i = 0; i < pa.size(); ++i)
    for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(pa[i][k] - pb[i][k]));
  EXPECT_LT(worst, 0.0005);  // half the declared 1 mm precision
}

TEST(Builder, ZeroExtentAxisAndSinglePoint) {
  TempDir tmp;
  SyntheticSpec plane;
  plane.shape = SyntheticShape::Plane;
  plane.points = 100000;
  BuildReport r = build(plane, quietOptions(tmp.path() / "plane"));
  EXPECT_EQ(r.metadata.points, 100000u);
  EXPECT_EQ(r.metadata.bounds.min.z, r.metadata.bounds.max.z);
  expectVerified(tmp.path() / "plane");

  SyntheticSpec one;
  one.points = 1;
  r = build(one, quietOptions(tmp.path() / "one"));
  EXPECT_EQ(r.metadata.points, 1u);
  EXPECT_EQ(r.metadata.nodes, 1u);
  expectVerified(tmp.path() / "one");
}

TEST(Builder, NonFiniteCoordinatesAreRejectedAndCounted) {
  TempDir tmp;
  nestlight::test::writeFile(tmp.file("p.xyz"),
                             "1 2 3\nnan 2 3\n4 inf 6\n7 8 9\n-inf 0 0\n10 11 12\n");
  std::vector<std::unique_ptr<PointReader>> r;
  r.push_back(openReader(tmp.file("p.xyz")));
  BuildReport rep = buildOctree(std::move(r), quietOptions(tmp.path() / "o"));
  EXPECT_EQ(rep.metadata.accounting.input, 6u);
  EXPECT_EQ(rep.metadata.points, 3u);
  EXPECT_EQ(rep.metadata.accounting.rejected.at(reject::kNonFinite), 3u);
  expectVerified(tmp.path() / "o");
}

TEST(Builder, NoPointsAtAll) {
  TempDir tmp;
  SyntheticSpec none;
  none.points = 0;
  BuildReport r = build(none, quietOptions(tmp.path() / "o"));
  EXPECT_EQ(r.metadata.points, 0u);
  expectVerified(tmp.path() / "o");
}

TEST(Builder, ChunkedBuildEqualsInMemoryBuildByteForByte) {
  TempDir tmp;
  SyntheticSpec spec;
  spec.points = 2000000;
  spec.seed = 11;
  BuildOptions small = quietOptions(tmp.path() / "chunked");
  small.memoryBytes = 24ull << 20;  // far below the input's ~60 MB
  BuildReport a = build(spec, small);
  EXPECT_GT(a.chunks, 4u);
  BuildOptions mem = quietOptions(tmp.path() / "memory");
  mem.inMemory = true;
  BuildReport b = build(spec, mem);
  EXPECT_EQ(b.chunks, 1u);
  expectVerified(tmp.path() / "chunked");
  // Payloads are appended in thread-timing order, so compare node by node: same nodes, same
  // payload bytes (checksums).
  OctreeReader ra(tmp.path() / "chunked"), rb(tmp.path() / "memory");
  auto na = ra.allNodes(), nb = rb.allNodes();
  ASSERT_EQ(na.size(), nb.size());
  for (size_t i = 0; i < na.size(); ++i) {
    ASSERT_EQ(na[i].first, nb[i].first);
    EXPECT_EQ(na[i].second.numPoints, nb[i].second.numPoints) << na[i].first.name();
    EXPECT_EQ(na[i].second.checksum, nb[i].second.checksum) << na[i].first.name();
  }
}

TEST(Builder, ResultIndependentOfInputOrder) {
  TempDir tmp;
  SyntheticSpec s1, s2;
  s1.points = s2.points = 150000;
  s1.seed = 1;
  s2.seed = 2;
  s2.origin = {30, 0, 0};
  auto run = [&](bool swap, const char* name) {
    std::vector<std::unique_ptr<PointReader>> r;
    r.push_back(openSynthetic(swap ? s2 : s1));
    r.push_back(openSynthetic(swap ? s1 : s2));
    return buildOctree(std::move(r), quietOptions(tmp.path() / name));
  };
  run(false, "ab");
  run(true, "ba");
  OctreeReader a(tmp.path() / "ab"), b(tmp.path() / "ba");
  auto na = a.allNodes(), nb = b.allNodes();
  ASSERT_EQ(na.size(), nb.size());
  for (size_t i = 0; i < na.size(); ++i) {
    ASSERT_EQ(na[i].first, nb[i].first);
    EXPECT_EQ(na[i].second.checksum, nb[i].second.checksum) << na[i].first.name();
  }
}

TEST(Builder, EstimatedNormalsAreUnitAndMarked) {
  TempDir tmp;
  SyntheticSpec plane;
  plane.shape = SyntheticShape::Plane;
  plane.points = 50000;
  BuildOptions o = quietOptions(tmp.path() / "o");
  o.estimateNormals = true;
  o.normalOrientation = NormalOrientation::Up;
  BuildReport r = build(plane, o);
  EXPECT_TRUE(r.metadata.normalsEstimated);
  OctreeReader reader(tmp.path() / "o");
  const int ni = reader.metadata().layout.find("normal");
  ASSERT_GE(ni, 0);
  const size_t off = reader.metadata().layout.offset(ni);
  size_t checked = 0;
  for (auto& [k, e] : reader.allNodes()) {
    PointBuffer p = reader.readNode(k);
    for (size_t i = 0; i < p.size(); ++i, ++checked) {
      float n[3];
      std::memcpy(n, p.attrsOf(i) + off, 12);
      // A flat plane: the fit is exact up to float rounding, and "up" orients it to +z.
      EXPECT_NEAR(n[2], 1.0f, 1e-5f);
    }
  }
  EXPECT_EQ(checked, 50000u);
}

TEST(Builder, InterruptedWriteLeavesNothingVerifyAccepts) {
  TempDir tmp;
  {
    PointLayout l;
    OctreeWriter w(tmp.path() / "o", l, Codec::Zstd, false);
    PointBuffer p(0);
    uint32_t pos[3] = {0, 0, 0};
    p.push(pos, nullptr);
    w.writeNode(NodeKey::root(), p);
    // Destroyed without finish(): as if the process died.
  }
  EXPECT_FALSE(fs::exists(tmp.path() / "o" / "metadata.json"));
  EXPECT_FALSE(verifyOctree(tmp.path() / "o").ok());
}

TEST(Builder, DamagedPayloadFailsVerify) {
  TempDir tmp;
  SyntheticSpec spec;
  spec.points = 50000;
  build(spec, quietOptions(tmp.path() / "o"));
  {
    std::fstream f(tmp.path() / "o" / "octree.bin",
                   std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(100);
    char c = 0x5a;
    f.write(&c, 1);
  }
  VerifyReport v = verifyOctree(tmp.path() / "o");
  ASSERT_FALSE(v.ok());
  EXPECT_NE(v.failures[0].find("checksum"), std::string::npos) << v.failures[0];
}

TEST(Builder, RefusesToOverwriteWithoutFlag) {
  TempDir tmp;
  SyntheticSpec spec;
  spec.points = 1000;
  build(spec, quietOptions(tmp.path() / "o"));
  EXPECT_THROW(build(spec, quietOptions(tmp.path() / "o")), Error);
  BuildOptions o = quietOptions(tmp.path() / "o");
  o.overwrite = true;
  EXPECT_NO_THROW(build(spec, o));
}

TEST(Builder, SampledCountingNeverLosesSparsePoints) {
  // LAS counting decodes one record in 8; isolated points that the sample misses must still get
  // a chunk. A dense cluster plus a few far outliers, with a small memory budget.
  TempDir tmp;
  SourceHeader h;
  h.layout.add({"intensity", ScalarType::U16, 1, ""});
  h.scale = Vec3d{0.001, 0.001, 0.001};
  h.offset = Vec3d{0, 0, 0};
  auto w = createLasWriter(tmp.file("s.las"), h);
  PointBatch b;
  uint64_t n = 0;
  auto add = [&](double x, double y, double z, uint16_t v) {
    b.xyz.insert(b.xyz.end(), {x, y, z});
    b.attrs.insert(b.attrs.end(), {uint8_t(v), uint8_t(v >> 8)});
    ++n;
  };
  // Record 0 is in the sample; records 1-7 are not. Put one outlier alone in each of the other
  // seven octants of the root, so the sampled count sees those octants empty.
  add(1, 1, 1, 0);
  for (int c = 1; c < 8; ++c) add(c & 4 ? 500 : 1, c & 2 ? 500 : 1, c & 1 ? 500 : 1, uint16_t(c));
  for (int i = 0; i < 400000; ++i)
    add(10.0 + (i % 631) * 0.003, 10.0 + (i / 631) * 0.003, 5.0 + (i % 7) * 0.001, uint16_t(i));
  w->write(b);
  w->close();
  std::vector<std::unique_ptr<PointReader>> r;
  r.push_back(openReader(tmp.file("s.las")));
  BuildOptions o = quietOptions(tmp.path() / "o");
  o.memoryBytes = 16ull << 20;
  BuildReport rep = buildOctree(std::move(r), o);
  EXPECT_EQ(rep.metadata.points, n);
  expectVerified(tmp.path() / "o");
}

TEST(Builder, EveryCodecAndSamplingRoundTrips) {
  SyntheticSpec spec;
  spec.points = 120000;
  spec.normals = true;
  auto src = openSynthetic(spec);
  for (Codec codec : {Codec::Raw, Codec::Zstd, Codec::Draco})
    for (Sampling sampling : {Sampling::Poisson, Sampling::Grid}) {
      TempDir tmp;
      BuildOptions o = quietOptions(tmp.path() / "o");
      o.codec = codec;
      o.sampling = sampling;
      BuildReport r = build(spec, o);
      SCOPED_TRACE(std::string(codecName(codec)) +
                   (sampling == Sampling::Grid ? " grid" : " poisson"));
      expectVerified(tmp.path() / "o");
      EXPECT_EQ(storedRecords(tmp.path() / "o"), sourceRecords(*src, r.metadata));
      OctreeReader reader(tmp.path() / "o");
      for (auto& [k, e] : reader.allNodes()) EXPECT_LE(e.numPoints, o.maxNodePoints) << k.name();
    }
}

TEST(Builder, ChunkedEqualsInMemoryWhenDedupShrinksASubtree) {
  // 15,000 distinct points, each six times: planning sees 90,000 and splits the root into
  // chunks, but after --dedup the whole scan fits one leaf, as the in-memory build makes it.
  TempDir tmp;
  SourceHeader h;
  h.scale = Vec3d{0.001, 0.001, 0.001};
  h.offset = Vec3d{0, 0, 0};
  auto w = createLasWriter(tmp.file("d.las"), h);
  PointBatch b;
  for (int copy = 0; copy < 6; ++copy)
    for (int i = 0; i < 15000; ++i)
      b.xyz.insert(b.xyz.end(), {(i % 123) * 0.05, (i / 123) * 0.05, (i % 7) * 0.025});
  w->write(b);
  w->close();
  auto run = [&](const char* name, bool inMemory) {
    std::vector<std::unique_ptr<PointReader>> r;
    r.push_back(openReader(tmp.file("d.las")));
    BuildOptions o = quietOptions(tmp.path() / name);
    o.dedup = true;
    o.memoryBytes = 16ull << 20;
    o.maxNodePoints = 20000;
    o.inMemory = inMemory;
    return buildOctree(std::move(r), o);
  };
  BuildReport chunked = run("chunked", false), memory = run("memory", true);
  EXPECT_GT(chunked.chunks, 1u);
  EXPECT_EQ(chunked.metadata.points, 15000u);
  EXPECT_EQ(chunked.metadata.accounting.duplicatesMerged, 75000u);
  expectVerified(tmp.path() / "chunked");
  OctreeReader a(tmp.path() / "chunked"), m(tmp.path() / "memory");
  auto na = a.allNodes(), nm = m.allNodes();
  ASSERT_EQ(na.size(), nm.size());
  EXPECT_EQ(na.size(), 1u);  // one leaf: the root
  for (size_t i = 0; i < na.size(); ++i) {
    EXPECT_EQ(na[i].first, nm[i].first);
    EXPECT_EQ(na[i].second.checksum, nm[i].second.checksum);
  }
}

namespace {

// Every stored point's world position in steps of 1 mm, sorted.
std::vector<std::array<int64_t, 3>> worldSteps(const fs::path& dir) {
  OctreeReader r(dir);
  const Metadata& m = r.metadata();
  std::vector<std::array<int64_t, 3>> out;
  for (auto& [k, e] : r.allNodes()) {
    PointBuffer p = r.readNode(k);
    for (size_t i = 0; i < p.size(); ++i) {
      std::array<int64_t, 3> w;
      for (int a = 0; a < 3; ++a) w[a] = std::llround(m.world(a, double(p.pos[3 * i + a])) / 0.001);
      out.push_back(w);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

BuildReport buildFile(const std::string& path, const BuildOptions& o) {
  std::vector<std::unique_ptr<PointReader>> r;
  r.push_back(openReader(path));
  return buildOctree(std::move(r), o);
}

}  // namespace

// Header bounds are advisory: bounds computed before quantisation sit up to half a scale step
// inside the stored points (a COPC writer's lion_takanawa does), and a header may lie by far
// more. Every finite point is kept either way, with the same stored positions as a file whose
// header is right; only points beyond half a step are a warning, with the farthest distance.
TEST(Builder, HeaderBoundsAreAdvisoryEveryFinitePointIsKept) {
  TempDir tmp;
  SyntheticSpec spec;
  spec.points = 40000;
  spec.precision = 0.001;
  test::writeLasWithBoundsInset(spec, tmp.file("true.las"), 0);
  test::writeLasWithBoundsInset(spec, tmp.file("half.las"), 0.0005);
  test::writeLasWithBoundsInset(spec, tmp.file("lying.las"), 7.5);
  buildFile(tmp.file("true.las"), quietOptions(tmp.path() / "true"));
  const auto want = worldSteps(tmp.path() / "true");
  ASSERT_EQ(want.size(), 40000u);
  for (const char* name : {"half", "lying"}) {
    SCOPED_TRACE(name);
    BuildReport r =
        buildFile(tmp.file(std::string(name) + ".las"), quietOptions(tmp.path() / name));
    const Accounting& a = r.metadata.accounting;
    EXPECT_EQ(a.input, 40000u);
    EXPECT_EQ(a.kept, 40000u);
    EXPECT_EQ(a.rejectedTotal(), 0u);
    EXPECT_TRUE(verifyOctree(tmp.path() / name).ok());
    // Stored world positions (in millimetre steps) equal those of the honest file's octree.
    EXPECT_EQ(worldSteps(tmp.path() / name), want);
    const auto& warnings = r.metadata.sources.at(0).warnings;
    if (std::string(name) == "half") {
      EXPECT_FALSE(test::anyContains(warnings, "outside the bounds"))
          << "within half a step is rounding";
    } else {
      EXPECT_TRUE(test::anyContains(warnings,
                                    "points lie outside the bounds the header declares, up to 7.5"))
          << (warnings.empty() ? "" : warnings.front());
      EXPECT_TRUE(test::anyContains(r.warnings, "measured from the points"));
    }
  }
}

// Each axis keeps its own scale and offset through the octree and out of export: LAS files with
// three different per-axis scales (one of them the 1_4_w_evlr twin's 1.1645e-6 / 1.003e-6, at
// national-grid coordinates) come back bit for bit, as the same integer coordinates and the same
// doubles. A single grid of the finest scale would move about a third of such points.
TEST(Builder, PerAxisScalesRoundTripBitForBit) {
  TempDir tmp;
  const std::array<Vec3d, 3> scales = {Vec3d{1.1645e-6, 1.1645e-6, 1.003e-6},
                                       Vec3d{0.01, 0.001, 0.0025}, Vec3d{0.00025, 0.003, 0.0001}};
  const std::array<Vec3d, 3> offsets = {Vec3d{500000, 5000000, 0}, Vec3d{-12.5, 3, 100},
                                        Vec3d{0, 0, 0}};
  for (int f = 0; f < 3; ++f) {
    SCOPED_TRACE(f);
    SyntheticSpec spec;
    spec.points = 20000;
    spec.seed = 7 + f;
    spec.size = f == 0 ? 0.5 : 50;  // a 1e-6 grid spans 2^31 steps in about 2 km
    spec.origin = {offsets[f].x + 0.1234567, offsets[f].y + 0.7654321, offsets[f].z + 0.5};
    spec.precision = 0;  // not on any grid: the LAS writer quantises
    auto r = openSynthetic(spec);
    SourceHeader h = r->header();
    h.scale = scales[f];
    h.offset = offsets[f];
    const std::string in = tmp.file("in" + std::to_string(f) + ".las"),
                      out = tmp.file("out" + std::to_string(f) + ".las");
    {
      auto w = createLasWriter(in, h);
      PointBatch b;
      while (r->read(b, 5000)) w->write(b);
      w->close();
    }
    const fs::path oct = tmp.path() / ("o" + std::to_string(f));
    BuildReport rep = buildFile(in, quietOptions(oct));
    EXPECT_EQ(rep.metadata.scale, scales[f]);
    EXPECT_EQ(exportOctree(oct, out), 20000u);
    // The same header scale and offset, and the same records' coordinates, as sorted triples of
    // the integers and of the doubles the reader makes of them.
    auto coordinates = [](const std::string& path, Vec3d& scale, Vec3d& offset) {
      auto rd = openReader(path);
      scale = *rd->header().scale;
      offset = *rd->header().offset;
      std::vector<std::array<double, 3>> xyz;
      PointBatch b;
      while (rd->read(b, 5000))
        for (size_t i = 0; i < b.size(); ++i)
          xyz.push_back({b.xyz[3 * i], b.xyz[3 * i + 1], b.xyz[3 * i + 2]});
      std::sort(xyz.begin(), xyz.end());
      return xyz;
    };
    Vec3d sa, oa, sb, ob;
    const auto a = coordinates(in, sa, oa), b = coordinates(out, sb, ob);
    EXPECT_EQ(sa, sb);
    EXPECT_EQ(oa, ob);
    ASSERT_EQ(a.size(), b.size());
    size_t moved = 0;
    for (size_t i = 0; i < a.size(); ++i) moved += a[i] != b[i];
    EXPECT_EQ(moved, 0u) << "of " << a.size();
    // The info note when inputs of different scales merge: the finest of each axis.
    if (f == 2) {
      std::vector<std::unique_ptr<PointReader>> both;
      both.push_back(openReader(tmp.file("in1.las")));
      both.push_back(openReader(in));
      BuildReport merged = buildOctree(std::move(both), quietOptions(tmp.path() / "merged"));
      EXPECT_EQ(merged.metadata.scale, (Vec3d{0.00025, 0.001, 0.0001}));
      EXPECT_TRUE(test::anyContains(merged.warnings,
                                    "keeps the finest of each axis (0.00025, 0.001, 1e-04)"))
          << (merged.warnings.empty() ? "no warnings" : merged.warnings.front());
      ASSERT_TRUE(merged.metadata.build.contains("notes"));
    }
  }
}
