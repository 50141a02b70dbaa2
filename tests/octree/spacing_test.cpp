// The measured point spacing stored in format version 2 hierarchy entries: the estimator on sets
// whose spacing is known, and its one-byte encoding.
#include "nestlight/octree/spacing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "nestlight/octree/hierarchy.h"

using namespace nestlight;

namespace {

uint64_t morton(uint32_t x, uint32_t y, uint32_t z) {
  uint64_t m = 0;
  for (int b = 0; b < 21; ++b)
    m |= (uint64_t(x >> b & 1) << (3 * b + 2)) | (uint64_t(y >> b & 1) << (3 * b + 1)) |
         (uint64_t(z >> b & 1) << (3 * b));
  return m;
}

// Points on the plane z = 7 in Morton order, as the builder hands them over.
std::vector<uint32_t> sortedPlane(std::vector<std::array<uint32_t, 3>> pts) {
  std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) {
    return morton(a[0], a[1], a[2]) < morton(b[0], b[1], b[2]);
  });
  std::vector<uint32_t> flat;
  for (auto& p : pts) flat.insert(flat.end(), p.begin(), p.end());
  return flat;
}

}  // namespace

TEST(Spacing, RegularGridMeasuresItsStep) {
  std::vector<std::array<uint32_t, 3>> pts;
  for (uint32_t y = 0; y < 120; ++y)
    for (uint32_t x = 0; x < 120; ++x) pts.push_back({x * 10, y * 10, 7});
  const auto xyz = sortedPlane(pts);
  // The 6th neighbour of a grid point lies at sqrt(2) steps: sqrt(2 pi / 6) = 1.023 steps.
  EXPECT_NEAR(medianNeighbourSpacing(xyz.data(), nullptr, pts.size()),
              10.0 * std::sqrt(2 * M_PI / 6), 1e-9);
}

TEST(Spacing, JitteredGridMeasuresItsStepWhereNearestNeighboursDoNot) {
  // A jittered grid (a terrestrial scanner's pattern with noise) has the density of its step;
  // its nearest neighbours are closer than that, which sized splats too small (holes).
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> jitter(-3, 3);
  std::vector<std::array<uint32_t, 3>> pts;
  for (uint32_t y = 1; y < 150; ++y)
    for (uint32_t x = 1; x < 150; ++x)
      pts.push_back({uint32_t(std::lround(x * 10 + jitter(rng))),
                     uint32_t(std::lround(y * 10 + jitter(rng))), 7});
  const auto xyz = sortedPlane(pts);
  const double s = medianNeighbourSpacing(xyz.data(), nullptr, pts.size());
  // The step is 10; the estimator's spread on this pattern is a few percent.
  EXPECT_GT(s, 9.5);
  EXPECT_LT(s, 11.5);
}

TEST(Spacing, IndicesSelectTheSetAndDegenerateSetsAreUnknown) {
  std::vector<std::array<uint32_t, 3>> pts;
  // A step that is no power of two: a grid aligned with the Morton blocks of the integer grid
  // hides diagonal neighbours beyond the search window (a limit of the window, documented).
  for (uint32_t y = 0; y < 64; ++y)
    for (uint32_t x = 0; x < 64; ++x) pts.push_back({x * 10, y * 10, 0});
  const auto xyz = sortedPlane(pts);
  // The checkerboard half of the grid (a grid turned 45 degrees, its step x sqrt(2)): spacing x
  // sqrt(2).
  std::vector<uint32_t> half;
  for (uint32_t i = 0; i < pts.size(); ++i)
    if ((xyz[3 * i] / 10 + xyz[3 * i + 1] / 10) % 2 == 0) half.push_back(i);
  const double all = medianNeighbourSpacing(xyz.data(), nullptr, pts.size());
  const double sub = medianNeighbourSpacing(xyz.data(), half.data(), half.size());
  ASSERT_EQ(half.size(), pts.size() / 2);
  EXPECT_NEAR(sub / all, std::sqrt(2.0), 0.01) << sub << " " << all;
  // A million coincident points are one point on screen: nothing to measure.
  std::vector<uint32_t> same(3 * 100000, 5);
  EXPECT_EQ(medianNeighbourSpacing(same.data(), nullptr, 100000), 0.0);
  EXPECT_EQ(medianNeighbourSpacing(xyz.data(), nullptr, 1), 0.0);
  // Each point of the grid three times over (kept apart by their attributes): the same spacing.
  std::vector<std::array<uint32_t, 3>> tripled;
  for (auto& p : pts) tripled.insert(tripled.end(), {p, p, p});
  const auto xyz3 = sortedPlane(tripled);
  EXPECT_NEAR(medianNeighbourSpacing(xyz3.data(), nullptr, tripled.size(), 128, 96), all,
              0.02 * all);
  EXPECT_EQ(medianNeighbourSpacing(xyz.data(), nullptr, 0), 0.0);
}

// Stray returns in bunches (the two "points" above the Takanawa lion are 4 and 6 returns within
// 1 cm, 0.4 m apart, in a node of little else): each bunch's own density counts, not the distance
// to the next bunch, which sized them as discs 65 pixels wide (issue 30).
TEST(Spacing, BunchedStrayReturnsMeasureTheirBunchNotTheGapBetween) {
  std::vector<std::array<uint32_t, 3>> pts;
  for (uint32_t b = 0; b < 20; ++b)
    for (uint32_t k = 0; k < 4; ++k)  // 4 returns 2 units apart, bunches 1000 units apart
      pts.push_back({1000 * (b % 5) + 2 * (k & 1), 1000 * (b / 5) + 2 * (k >> 1), 7});
  const auto xyz = sortedPlane(pts);
  const double s = medianNeighbourSpacing(xyz.data(), nullptr, pts.size());
  // Without the rule: the 6th neighbour is the next bunch, 1000 sqrt(pi / 6) = 724. With it: the
  // bunch's own, its 3rd neighbour (the square's diagonal, 2 sqrt(2)) giving sqrt(8 pi / 3) = 2.9.
  EXPECT_NEAR(s, std::sqrt(8 * M_PI / 3), 1e-9);
}

// Points scattered at random on a plane (a 2D Poisson process of density 1/100, spacing 10): the
// bunch rule applies to about 1% of queries, so the median stays the k-th-neighbour one's: pi r_6^2
// density follows Gamma(6, 1), median 5.67, so the estimate's median is sqrt(5.67 / 6) = 0.97 of
// the spacing; the window's missed neighbours add a few percent. Within [0.9, 1.1] x 10.
TEST(Spacing, RandomPlaneKeepsItsDensityUnderTheBunchCap) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<uint32_t> u(0, 1999);
  std::vector<std::array<uint32_t, 3>> pts;
  for (int i = 0; i < 40000; ++i) pts.push_back({u(rng), u(rng), 7});  // 4e6 / 4e4 = 100 per point
  const auto xyz = sortedPlane(pts);
  const double s = medianNeighbourSpacing(xyz.data(), nullptr, pts.size(), 4096);
  EXPECT_GT(s, 9.0);
  EXPECT_LT(s, 11.0);
}

TEST(Spacing, OneByteCodeKeepsTheRatioWithinHalfAStep) {
  const double step = std::exp2(1.0 / 16);
  for (double ratio = 1.0 / 200; ratio < 200; ratio *= 1.37) {
    const uint8_t code = encodeSpacing(ratio * 0.25, 0.25);
    ASSERT_NE(code, 0);
    const double back = decodeSpacing(code, 0.25) / 0.25;
    EXPECT_LE(std::max(back / ratio, ratio / back), std::sqrt(step) * (1 + 1e-12)) << ratio;
  }
  EXPECT_EQ(encodeSpacing(1.0, 1.0), 128);
  // Out of range clamps; unknown stays unknown.
  EXPECT_EQ(encodeSpacing(1e9, 1.0), 255);
  EXPECT_EQ(encodeSpacing(1e-9, 1.0), 1);
  EXPECT_EQ(encodeSpacing(0, 1.0), 0);
  EXPECT_EQ(encodeSpacing(NAN, 1.0), 0);
  EXPECT_EQ(encodeSpacing(1.0, 0), 0);
  EXPECT_EQ(decodeSpacing(0, 3.0), 0.0);
}

TEST(Spacing, HierarchyEntriesRoundTripTheCode) {
  std::vector<NodeRecord> nodes;
  nodes.push_back({NodeKey::root(), Codec::Zstd, 10, 0, 100, 1, 140});
  nodes.push_back({NodeKey::root().child(3), Codec::Zstd, 20, 100, 50, 2, 97});
  HierarchyBlob blob = buildHierarchy(nodes);
  std::vector<std::pair<NodeKey, HierarchyEntry>> out;
  ASSERT_EQ(parseHierarchyChunk(blob.bytes.data(), blob.bytes.size(), NodeKey::root(),
                                kHierarchyStep, out),
            "");
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].second.spacingCode, 140);
  EXPECT_EQ(out[1].second.spacingCode, 97);
}
