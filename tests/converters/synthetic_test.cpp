// Synthetic point source: determinism (batch sizes, rewind), counts, bounds, special shapes,
// (its speed is measured by benchmarks, not tests).
#include "nestlight/converters/synthetic.h"

#include <time.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "nestlight/converters/synthetic_octree.h"
#include "nestlight/octree/octree_reader.h"
#include "test_support.h"

namespace nestlight {
namespace {

struct SyntheticPoints {
  std::vector<double> xyz;
  std::vector<uint8_t> attrs;
  size_t batches = 0;
};

SyntheticPoints readSynthetic(PointReader& r, size_t batchSize) {
  SyntheticPoints out;
  PointBatch b;
  while (r.read(b, batchSize)) {
    EXPECT_LE(b.size(), batchSize);
    EXPECT_EQ(b.attrs.size(), b.size() * r.header().layout.stride());
    out.xyz.insert(out.xyz.end(), b.xyz.begin(), b.xyz.end());
    out.attrs.insert(out.attrs.end(), b.attrs.begin(), b.attrs.end());
    ++out.batches;
  }
  return out;
}

SyntheticSpec spec(SyntheticShape shape, uint64_t points) {
  SyntheticSpec s;
  s.shape = shape;
  s.points = points;
  s.normals = true;
  return s;
}

TEST(Synthetic, DeterministicAcrossBatchSizesAndRewind) {
  for (auto shape : {SyntheticShape::Surfaces, SyntheticShape::Cube, SyntheticShape::Plane}) {
    SyntheticSpec s = spec(shape, 300'001);  // large batches take the parallel path
    s.seed = 42;
    auto a = openSynthetic(s);
    auto b = openSynthetic(s);
    const SyntheticPoints big = readSynthetic(*a, 1'000'000);
    const SyntheticPoints small = readSynthetic(*b, 1000);
    EXPECT_EQ(big.batches, 1u);
    EXPECT_EQ(small.batches, 301u);
    EXPECT_EQ(big.xyz, small.xyz);
    EXPECT_EQ(big.attrs, small.attrs);
    a->rewind();
    const SyntheticPoints again = readSynthetic(*a, 77'777);
    EXPECT_EQ(big.xyz, again.xyz);
    EXPECT_EQ(big.attrs, again.attrs);

    s.seed = 43;
    const SyntheticPoints other = readSynthetic(*openSynthetic(s), 1'000'000);
    EXPECT_NE(big.xyz, other.xyz);
  }
}

TEST(Synthetic, CountsAndHeader) {
  for (uint64_t n : {uint64_t(0), uint64_t(1), uint64_t(12'345)}) {
    auto r = openSynthetic(spec(SyntheticShape::Surfaces, n));
    const SourceHeader& h = r->header();
    EXPECT_EQ(h.format, "synthetic");
    EXPECT_EQ(*h.declaredPoints, n);
    EXPECT_EQ(h.rgbBits, 8);
    ASSERT_EQ(h.layout.size(), 3u);
    EXPECT_EQ(h.layout[0], (Attribute{"rgb", ScalarType::U16, 3, ""}));
    EXPECT_EQ(h.layout[1], (Attribute{"intensity", ScalarType::U16, 1, ""}));
    EXPECT_EQ(h.layout[2], (Attribute{"normal", ScalarType::F32, 3, ""}));
    const SyntheticPoints all = readSynthetic(*r, 1000);
    EXPECT_EQ(all.xyz.size(), n * 3);
    EXPECT_EQ(r->bytesConsumed(), r->bytesTotal());
  }
  SyntheticSpec bare = spec(SyntheticShape::Cube, 10);
  bare.rgb = bare.intensity = bare.normals = false;
  auto r = openSynthetic(bare);
  EXPECT_EQ(r->header().layout.size(), 0u);
  EXPECT_EQ(r->header().rgbBits, 0);
  EXPECT_EQ(readSynthetic(*r, 3).xyz.size(), 30u);
}

TEST(Synthetic, PointsInsideDeclaredBoundsAndOnTheGrid) {
  for (auto shape : {SyntheticShape::Surfaces, SyntheticShape::Cube, SyntheticShape::Plane,
                     SyntheticShape::Duplicates}) {
    SyntheticSpec s = spec(shape, 200'000);
    s.origin = {500000, 5000000, 100};  // national grid
    s.noise = 0.05;
    auto r = openSynthetic(s);
    const Box3d box = *r->header().declaredBounds;
    const SyntheticPoints all = readSynthetic(*r, 65'536);
    Box3d seen;
    for (size_t i = 0; i < all.xyz.size(); i += 3) {
      const double x = all.xyz[i], y = all.xyz[i + 1], z = all.xyz[i + 2];
      ASSERT_TRUE(box.contains(x, y, z))
          << syntheticShapeName(shape) << " " << x << " " << y << " " << z;
      seen.extend(x, y, z);
      // On the millimetre grid relative to the origin.
      for (int a = 0; a < 3; ++a) {
        const double k = (all.xyz[i + a] - s.origin[a]) / s.precision;
        ASSERT_NEAR(k, std::round(k), 1e-3);
      }
    }
    // The bounds are tight up to the noise margin.
    for (int a = 0; a < 3; ++a) {
      const double slack = shape == SyntheticShape::Surfaces ? 4 * s.noise + 0.01 : 0.01;
      EXPECT_LE(seen.min[a] - box.min[a], slack) << syntheticShapeName(shape) << " axis " << a;
      EXPECT_LE(box.max[a] - seen.max[a], slack) << syntheticShapeName(shape) << " axis " << a;
    }
  }
}

TEST(Synthetic, DuplicatesAreIdentical) {
  SyntheticSpec s = spec(SyntheticShape::Duplicates, 5000);
  s.origin = {10, 20, 30};
  auto r = openSynthetic(s);
  const SyntheticPoints all = readSynthetic(*r, 999);
  const size_t stride = r->header().layout.stride();
  for (size_t i = 0; i < 5000; ++i) {
    ASSERT_EQ(all.xyz[i * 3 + 0], 60.0);
    ASSERT_EQ(all.xyz[i * 3 + 1], 70.0);
    ASSERT_EQ(all.xyz[i * 3 + 2], 80.0);
    ASSERT_EQ(std::memcmp(&all.attrs[i * stride], &all.attrs[0], stride), 0);
  }
  const Box3d box = *r->header().declaredBounds;
  EXPECT_EQ(box.min, (Vec3d{60, 70, 80}));
  EXPECT_EQ(box.max, (Vec3d{60, 70, 80}));
}

TEST(Synthetic, PlaneHasZeroZExtent) {
  SyntheticSpec s = spec(SyntheticShape::Plane, 100'000);
  s.origin = {500000, 5000000, 100.25};
  auto r = openSynthetic(s);
  const SyntheticPoints all = readSynthetic(*r, 4096);
  for (size_t i = 0; i < all.xyz.size(); i += 3) ASSERT_EQ(all.xyz[i + 2], 100.25);
  const Box3d box = *r->header().declaredBounds;
  EXPECT_EQ(box.min.z, 100.25);
  EXPECT_EQ(box.max.z, 100.25);
  EXPECT_GT(box.max.x - box.min.x, 99.0);
}

TEST(Synthetic, NormalsAreUnitLength) {
  for (auto shape : {SyntheticShape::Surfaces, SyntheticShape::Cube, SyntheticShape::Plane,
                     SyntheticShape::Duplicates}) {
    auto r = openSynthetic(spec(shape, 100'000));
    const PointLayout& l = r->header().layout;
    const size_t off = l.offset(size_t(l.find("normal")));
    const SyntheticPoints all = readSynthetic(*r, 100'000);
    for (size_t i = 0; i < 100'000; ++i) {
      float n[3];
      std::memcpy(n, &all.attrs[i * l.stride() + off], 12);
      ASSERT_NEAR(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), 1.0, 1e-5);
    }
  }
}

TEST(Synthetic, SurfacesColourVariesSmoothly) {
  // Not a constant (compression would be unrealistic) and not white noise: neighbouring points
  // in generation order are unrelated, so compare the spread of all colours with the spread of
  // colours within small cells.
  auto r = openSynthetic(spec(SyntheticShape::Surfaces, 200'000));
  const SyntheticPoints all = readSynthetic(*r, 200'000);
  const size_t stride = r->header().layout.stride();
  uint16_t lo = 65535, hi = 0;
  for (size_t i = 0; i < 200'000; ++i) {
    uint16_t red;
    std::memcpy(&red, &all.attrs[i * stride], 2);
    lo = std::min(lo, red), hi = std::max(hi, red);
  }
  EXPECT_GT(hi - lo, 100 * 257);
}

TEST(Synthetic, ParseShape) {
  EXPECT_EQ(parseSyntheticShape("surfaces"), SyntheticShape::Surfaces);
  EXPECT_EQ(parseSyntheticShape("Cube"), SyntheticShape::Cube);
  EXPECT_EQ(parseSyntheticShape("duplicates"), SyntheticShape::Duplicates);
  EXPECT_EQ(parseSyntheticShape("plane"), SyntheticShape::Plane);
  EXPECT_EQ(parseSyntheticShape("sphere"), std::nullopt);
  for (auto s : {SyntheticShape::Surfaces, SyntheticShape::Cube, SyntheticShape::Duplicates,
                 SyntheticShape::Plane})
    EXPECT_EQ(parseSyntheticShape(syntheticShapeName(s)), s);
}

}  // namespace
}  // namespace nestlight

TEST(SyntheticOctree, IsBuiltOnceAndRebuiltForAnotherSize) {
  nestlight::test::TempDir tmp;
  const auto dir = tmp.path() / "s.octree";
  ASSERT_EQ(nestlight::ensureSyntheticOctree(20'000, dir, true), dir);
  EXPECT_EQ(nestlight::OctreeReader(dir).metadata().points, 20'000u);
  const auto stamp = std::filesystem::last_write_time(dir / "metadata.json");
  nestlight::ensureSyntheticOctree(20'000, dir, true);  // reused: not written again
  EXPECT_EQ(std::filesystem::last_write_time(dir / "metadata.json"), stamp);
  nestlight::ensureSyntheticOctree(30'000, dir, true);
  EXPECT_EQ(nestlight::OctreeReader(dir).metadata().points, 30'000u);
}
