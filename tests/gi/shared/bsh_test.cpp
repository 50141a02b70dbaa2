// The bounding-sphere hierarchy's invariants (every child inside its parent's sphere, every
// normal inside its node's cone, the pruning thresholds respected, every point accounted for) on
// random and degenerate point sets; Morton codes and their radix sort; normal cones.
#include "nestlight/gi/shared/bsh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <functional>
#include <numeric>
#include <random>

#include "nestlight/frame/gl_node_store.h"
#include "nestlight/gi/shared/morton.h"
#include "nestlight/gi/shared/normal_cone.h"

namespace nestlight::gi {
namespace {

// Tolerances. Spheres: the builder widens radii by 8 ulps of the coordinates' magnitude for float
// rounding, so containment holds to 1e-6 relative; cones: stored apertures include the axis's
// 16-bit quantisation, so containment holds to 1e-5 rad (float rounding of the check itself).
constexpr float kSphereRel = 1e-6f;
constexpr float kConeSlack = 1e-5f;

float angle(const glm::vec3& a, const glm::vec3& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

glm::vec3 randomUnit(std::mt19937& rng) {
  std::normal_distribution<float> g;
  glm::vec3 v;
  do v = {g(rng), g(rng), g(rng)};
  while (glm::length(v) < 1e-3f);
  return glm::normalize(v);
}

TEST(Morton, InterleavesBitsZLowest) {
  EXPECT_EQ(mortonCode(0, 0, 1), 1u);
  EXPECT_EQ(mortonCode(0, 1, 0), 2u);
  EXPECT_EQ(mortonCode(1, 0, 0), 4u);
  EXPECT_EQ(mortonCode(0, 0, 3), 9u);
  EXPECT_EQ(mortonCode(kMortonAxisMax, kMortonAxisMax, kMortonAxisMax), (1ull << 63) - 1);
  // Bit k of z lands at 3k: the highest z bit at 60, x's at 62.
  EXPECT_EQ(mortonCode(0, 0, 1u << 20), 1ull << 60);
  EXPECT_EQ(mortonCode(1u << 20, 0, 0), 1ull << 62);
}

TEST(Morton, RadixSortMatchesStableSortWithDuplicates) {
  std::mt19937_64 rng(7);
  for (size_t n : {0, 1, 2, 1000, 100000}) {
    std::vector<uint64_t> keys(n);
    for (auto& k : keys)
      k = rng() % 3 == 0 ? (rng() & 0xff) : rng() >> (rng() % 40);  // many equal keys
    std::vector<uint32_t> values(n);
    std::iota(values.begin(), values.end(), 0u);
    std::vector<std::pair<uint64_t, uint32_t>> expected;
    for (size_t i = 0; i < n; ++i) expected.emplace_back(keys[i], values[i]);
    std::stable_sort(expected.begin(), expected.end(),
                     [](auto& a, auto& b) { return a.first < b.first; });
    radixSortPairs(keys, values);
    for (size_t i = 0; i < n; ++i) {
      ASSERT_EQ(keys[i], expected[i].first) << i;
      ASSERT_EQ(values[i], expected[i].second) << i;  // stable
    }
  }
}

TEST(NormalCone, MergeContainsBothAndIsTightForTwoNormals) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0, 1);
  for (int t = 0; t < 10000; ++t) {
    NormalCone a{randomUnit(rng), u(rng) * 1.5f}, b{randomUnit(rng), u(rng) * 1.5f};
    if (t % 3 == 0) a.halfAngle = 0;
    const NormalCone m = merge(a, b);
    ASSERT_TRUE(m.contains(a, kConeSlack)) << t;
    ASSERT_TRUE(m.contains(b, kConeSlack)) << t;
    // Minimal: neither inside the other, the merged aperture is half the angle they span.
    const float span = angle(a.axis, b.axis) + a.halfAngle + b.halfAngle;
    if (!a.contains(b) && !b.contains(a) && span < kPi * 2) {
      ASSERT_NEAR(m.halfAngle, std::min(kPi, span / 2), 1e-5f) << t;
    }
  }
  const NormalCone two = merge(NormalCone::of({1, 0, 0}), NormalCone::of({0, 1, 0}));
  EXPECT_NEAR(two.halfAngle, kPi / 4, 1e-6f);
  EXPECT_NEAR(angle(two.axis, glm::normalize(glm::vec3(1, 1, 0))), 0, 1e-6f);
}

TEST(NormalCone, OppositeNormalsGiveAHemisphereAndUnknownGivesEverything) {
  const NormalCone m = merge(NormalCone::of({0, 0, 1}), NormalCone::of({0, 0, -1}));
  EXPECT_NEAR(m.halfAngle, kPi / 2, 1e-6f);
  EXPECT_TRUE(m.contains(glm::vec3(0, 0, 1), kConeSlack));
  EXPECT_TRUE(m.contains(glm::vec3(0, 0, -1), kConeSlack));
  EXPECT_NEAR(glm::dot(m.axis, glm::vec3(0, 0, 1)), 0, 1e-6f);
  EXPECT_TRUE(NormalCone::of({0, 0, 0}).boundsNothing());
  EXPECT_TRUE(NormalCone::of({NAN, 0, 1}).boundsNothing());
  EXPECT_TRUE(merge(NormalCone::of({0, 0, 1}), NormalCone::everything()).boundsNothing());
  // Two cones wider than a hemisphere pointing apart: everything.
  EXPECT_TRUE(merge(NormalCone{{0, 0, 1}, 2.0f}, NormalCone{{0, 0, -1}, 2.0f}).boundsNothing());
}

// Checks every invariant of `bsh` against the points it was built from.
void checkInvariants(const BshPoints& pts, const BshOptions& opt, const Bsh& bsh) {
  const auto& nodes = bsh.nodes;
  ASSERT_EQ(bsh.leafOf.size(), pts.position.size());
  uint64_t accepted = 0;
  for (uint32_t l : bsh.leafOf) accepted += l != BSH_LEAF;
  ASSERT_EQ(accepted + bsh.stats.rejected, bsh.stats.input);
  if (accepted == 0) {
    EXPECT_TRUE(nodes.empty());
    return;
  }
  ASSERT_FALSE(nodes.empty());
  EXPECT_EQ(nodes[0].links.z, accepted);  // every accepted point below the root
  EXPECT_LE(bsh.stats.depth, BSH_MAX_DEPTH);
  EXPECT_EQ(bsh.stats.nodes, nodes.size());

  // Points of each leaf, and of each subtree (depth-first: a contiguous index range).
  std::vector<std::vector<uint32_t>> ofLeaf(nodes.size());
  for (uint32_t i = 0; i < bsh.leafOf.size(); ++i)
    if (bsh.leafOf[i] != BSH_LEAF) {
      ASSERT_LT(bsh.leafOf[i], nodes.size());
      ASSERT_TRUE(isLeaf(nodes[bsh.leafOf[i]]));
      ofLeaf[bsh.leafOf[i]].push_back(i);
    }
  // The Morton grid's cell diagonal (with rounding margin): points closer than this may share a
  // leaf without being a pruned cluster.
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (uint32_t i = 0; i < bsh.leafOf.size(); ++i)
    if (bsh.leafOf[i] != BSH_LEAF)
      lo = glm::min(lo, pts.position[i]), hi = glm::max(hi, pts.position[i]);
  const float extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  const float cellDiagonal =
      2.0f * std::sqrt(3.0f) * extent / float(kMortonAxisMax) + 1e-6f * glm::length(hi);
  std::vector<uint32_t> end(nodes.size());
  std::function<uint32_t(uint32_t, int)> walk = [&](uint32_t i, int depth) -> uint32_t {
    EXPECT_LE(depth, BSH_MAX_DEPTH);
    const BshNode& n = nodes[i];
    if (isLeaf(n)) return end[i] = i + 1;
    EXPECT_EQ(n.links.x, i + 1);
    const uint32_t e = walk(n.links.x, depth + 1);
    EXPECT_EQ(n.links.y, e);  // the right child follows the left subtree
    return end[i] = walk(n.links.y, depth + 1);
  };
  ASSERT_EQ(walk(0, 0), nodes.size());  // every node reached once

  for (uint32_t i = 0; i < nodes.size(); ++i) {
    const BshNode& n = nodes[i];
    const glm::vec3 c(n.sphere);
    const float r = n.sphere.w;
    const NormalCone cone{coneAxis(n), n.colour.w};
    if (!isLeaf(n)) {
      uint32_t count = 0;
      for (uint32_t ch : {n.links.x, n.links.y}) {
        const BshNode& k = nodes[ch];
        // Child inside parent: sphere and cone.
        EXPECT_LE(glm::length(glm::vec3(k.sphere) - c) + k.sphere.w, r * (1 + kSphereRel) + 1e-30f)
            << i << "->" << ch;
        const NormalCone kc{coneAxis(k), k.colour.w};
        if (!cone.boundsNothing()) {
          EXPECT_TRUE(cone.contains(kc, kConeSlack)) << i << "->" << ch;
        }
        count += k.links.z;
      }
      EXPECT_EQ(count, n.links.z);
    }
    // The points below: their discs inside the sphere, normals inside the cone, colour the mean;
    // and the pruning decision matches the thresholds.
    std::vector<uint32_t> below;
    for (uint32_t j = i; j < end[i]; ++j)
      below.insert(below.end(), ofLeaf[j].begin(), ofLeaf[j].end());
    ASSERT_EQ(below.size(), n.links.z) << i;
    glm::dvec3 sum(0), sum2(0), nsum(0);
    double withNormal = 0;
    for (uint32_t p : below) {
      const float disc = pts.radius.empty() ? opt.leafRadius : pts.radius[p];
      EXPECT_LE(glm::length(pts.position[p] - c) + disc, r * (1 + kSphereRel) + 1e-30f) << i;
      // An unpruned leaf's disc reaches as far as its points' discs.
      if (isLeaf(n) && !opt.prune) {
        EXPECT_GE(std::bit_cast<float>(n.links.y), disc * (1 - kSphereRel)) << i;
      }
      if (!pts.normal.empty()) {
        const NormalCone pc = NormalCone::of(pts.normal[p]);
        if (!pc.boundsNothing()) {
          EXPECT_TRUE(cone.contains(pc.axis, kConeSlack)) << i;
          nsum += glm::dvec3(pc.axis);
          withNormal += 1;
        } else {
          EXPECT_TRUE(cone.boundsNothing()) << i;
        }
      }
      sum += glm::dvec3(pts.colour[p]);
      sum2 += glm::dvec3(pts.colour[p]) * glm::dvec3(pts.colour[p]);
    }
    const double k = double(below.size());
    const glm::dvec3 mean = sum / k;
    for (int ch = 0; ch < 3; ++ch)
      EXPECT_NEAR(n.colour[ch], mean[ch], 1e-5 * std::max(1.0, mean[ch])) << i;
    if (!opt.prune) continue;
    const glm::dvec3 var = sum2 / k - mean * mean;
    const bool colourSimilar = std::max({var.r, var.g, var.b}) < opt.colourVariance;
    const bool normalSimilar = withNormal == 0
                                   ? !(withNormal < k && !pts.normal.empty() && withNormal > 0)
                                   : withNormal == k && glm::length(nsum) / k > opt.normalAgreement;
    // Within float and summation-order noise at the thresholds themselves.
    const bool nearThreshold =
        std::fabs(std::max({var.r, var.g, var.b}) - opt.colourVariance) < 1e-6 ||
        (withNormal > 0 && std::fabs(glm::length(nsum) / k - opt.normalAgreement) < 1e-6);
    if (nearThreshold) continue;
    if (isLeaf(n) && bsh.leafOf.size() && below.size() > 1) {
      // A leaf of several points is a Morton cell (points closer than 2^-21 of the extent) or a
      // pruned cluster: a cluster must meet both thresholds.
      const bool cell = [&] {
        for (uint32_t p : below)
          if (glm::length(pts.position[p] - pts.position[below[0]]) > cellDiagonal) return false;
        return true;
      }();
      if (!cell) {
        EXPECT_TRUE(colourSimilar && normalSimilar) << "cluster " << i << " var " << var.r;
      }
    }
    if (!isLeaf(n)) {
      EXPECT_FALSE(colourSimilar && normalSimilar)
          << "inner node " << i << " should have been pruned";
    }
  }
}

Bsh buildChecked(const BshPoints& pts, BshOptions opt) {
  opt.recordLeaves = true;
  Bsh bsh = buildBsh(pts, opt);
  checkInvariants(pts, opt, bsh);
  return bsh;
}

BshPoints randomPoints(size_t n, uint32_t seed, bool normals, float colourSpread) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  BshPoints p;
  for (size_t i = 0; i < n; ++i) {
    p.position.push_back({u(rng) * 4, u(rng) * 2, u(rng) * 3});
    p.colour.push_back(glm::vec3(0.5f) + colourSpread * (glm::vec3(u(rng), u(rng), u(rng)) - 0.5f));
    if (normals) p.normal.push_back(randomUnit(rng));
  }
  return p;
}

TEST(Bsh, InvariantsOnRandomPointsWithAndWithoutPruning) {
  for (bool normals : {true, false})
    for (bool prune : {true, false}) {
      SCOPED_TRACE(testing::Message() << "normals " << normals << " prune " << prune);
      const BshPoints pts = randomPoints(3000, 11, normals, 1.0f);
      BshOptions opt;
      opt.leafRadius = 0.02f;
      opt.prune = prune;
      const Bsh bsh = buildChecked(pts, opt);
      EXPECT_EQ(bsh.stats.leaves, 3000u);
      EXPECT_EQ(bsh.stats.nodesBeforePruning, 5999u);
      if (!prune) {
        EXPECT_EQ(bsh.nodes.size(), 5999u);
      }
    }
}

// Per-point disc radii (diffrender's exact query: the reference's): every sphere holds each
// point's own disc, and an unpruned leaf's disc is as wide as its point's.
TEST(Bsh, PerPointRadiiAreHeld) {
  for (bool prune : {true, false}) {
    BshPoints pts = randomPoints(2000, 5, true, 0.2f);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, 0.2f);
    for (size_t i = 0; i < pts.position.size(); ++i) pts.radius.push_back(u(rng));
    BshOptions opt;
    opt.leafRadius = 0.01f;  // not used: every point has its own
    opt.prune = prune;
    buildChecked(pts, opt);
  }
}

// A sphere's surface, normals outward, uniform colour: pruning merges sub-trees where the surface
// is flat enough (normals within ~11 degrees), never across the sphere.
TEST(Bsh, UniformSpherePrunesLocallyFlatPatchesOnly) {
  std::mt19937 rng(5);
  BshPoints pts;
  for (int i = 0; i < 20000; ++i) {
    const glm::vec3 n = randomUnit(rng);
    pts.position.push_back(glm::vec3(2) + n);
    pts.normal.push_back(n);
    pts.colour.push_back(glm::vec3(0.3f, 0.6f, 0.9f));
  }
  BshOptions opt;
  opt.leafRadius = 0.01f;
  const Bsh bsh = buildChecked(pts, opt);
  EXPECT_GT(bsh.stats.clusters, 10u);
  EXPECT_LT(bsh.nodes.size(), bsh.stats.nodesBeforePruning / 4);  // flat patches collapse
  EXPECT_FALSE(isLeaf(bsh.nodes[0]));
  // The whole sphere: every direction, so the root's cone bounds nothing and has no axis.
  EXPECT_FLOAT_EQ(bsh.nodes[0].colour.w, float(BSH_CONE_NONE));
  EXPECT_EQ(coneAxis(bsh.nodes[0]), glm::vec3(0.0f));
  // Every cluster is a locally flat patch: its cone is narrow, its axis a unit vector.
  for (const BshNode& n : bsh.nodes)
    if (isLeaf(n) && n.links.z > 1) {
      EXPECT_LT(n.colour.w, 0.5f);
      EXPECT_NEAR(glm::length(coneAxis(n)), 1.0f, 1e-3f);
    }
}

TEST(Bsh, FlatUniformPlaneIsOneLeafAndTwoColoursAreNot) {
  BshPoints pts;
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 100; ++x) {
      pts.position.push_back({x * 0.01f, y * 0.01f, 0});
      pts.normal.push_back({0, 0, 1});
      pts.colour.push_back(glm::vec3(0.7f));
    }
  BshOptions opt;
  opt.leafRadius = 0.01f;
  Bsh one = buildChecked(pts, opt);
  ASSERT_EQ(one.nodes.size(), 1u);
  EXPECT_EQ(one.nodes[0].links.z, 10000u);
  EXPECT_LT(one.nodes[0].colour.w, 1e-3f);
  EXPECT_NEAR(glm::dot(coneAxis(one.nodes[0]), glm::vec3(0, 0, 1)), 1, 1e-6);
  // Half red, half green: variance 0.25 per channel, far above 0.01.
  for (size_t i = 0; i < pts.colour.size(); ++i)
    pts.colour[i] = pts.position[i].x < 0.5f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  Bsh two = buildChecked(pts, opt);
  EXPECT_FALSE(isLeaf(two.nodes[0]));
  // Noise just below the threshold (uniform +-0.17: variance 0.0096) still collapses.
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-0.17f, 0.17f);
  for (auto& c : pts.colour) c = glm::vec3(0.5f + u(rng));
  Bsh noisy = buildChecked(pts, opt);
  EXPECT_EQ(noisy.nodes.size(), 1u);
}

TEST(Bsh, DuplicatesByTheMillionAreOneCell) {
  BshPoints pts;
  pts.position.assign(1'000'000, glm::vec3(1.25f, -3.5f, 7.0f));
  pts.colour.assign(1'000'000, glm::vec3(0.2f));
  pts.normal.assign(1'000'000, glm::vec3(0, 1, 0));
  pts.position.push_back({2, 2, 2});  // and one other point
  pts.colour.push_back(glm::vec3(0.9f));
  pts.normal.push_back({1, 0, 0});
  BshOptions opt;
  opt.leafRadius = 0.0f;  // zero-radius leaves
  opt.prune = false;      // (pruned, the outlier's 1e-6 share of the colour would merge all)
  const Bsh bsh = buildChecked(pts, opt);
  EXPECT_EQ(bsh.stats.leaves, 2u);
  EXPECT_EQ(bsh.stats.sharedCells, 1'000'000u);
  ASSERT_EQ(bsh.nodes.size(), 3u);
  EXPECT_EQ(bsh.nodes[0].links.z, 1'000'001u);
  const BshNode& cell = bsh.nodes[bsh.leafOf[0]];
  EXPECT_EQ(cell.links.z, 1'000'000u);
  EXPECT_LT(cell.sphere.w, 1e-5f);  // a zero-radius node (only the rounding margin)
  EXPECT_NEAR(cell.colour.r, 0.2f, 1e-6f);
}

TEST(Bsh, DegenerateSetsKeepTheirInvariants) {
  BshOptions opt;
  opt.leafRadius = 0.05f;
  {  // collinear, two colours alternating
    BshPoints pts;
    for (int i = 0; i < 500; ++i) {
      pts.position.push_back({i * 0.1f, 0, 0});
      pts.colour.push_back(glm::vec3(float(i % 2)));
      pts.normal.push_back({0, 0, i % 3 == 0 ? -1.f : 1.f});  // opposite normals in one cone
    }
    const Bsh bsh = buildChecked(pts, opt);
    EXPECT_NEAR(bsh.nodes[0].colour.w, kPi / 2, 1e-3f);
  }
  {  // one point
    BshPoints pts;
    pts.position = {{1, 2, 3}};
    pts.colour = {{0.1f, 0.2f, 0.3f}};
    const Bsh bsh = buildChecked(pts, opt);
    ASSERT_EQ(bsh.nodes.size(), 1u);
    EXPECT_NEAR(bsh.nodes[0].sphere.w, 0.05f, 1e-5f);
    EXPECT_EQ(bsh.stats.depth, 0);
  }
  {  // nothing
    const Bsh bsh = buildChecked(BshPoints{}, opt);
    EXPECT_TRUE(bsh.nodes.empty());
  }
  {  // clustered: two tight clumps far apart, mixed known and unknown normals
    std::mt19937 rng(9);
    std::normal_distribution<float> g(0, 1e-4f);
    BshPoints pts;
    for (int i = 0; i < 2000; ++i) {
      pts.position.push_back(glm::vec3(i < 1000 ? 0.f : 100.f) + glm::vec3(g(rng), g(rng), g(rng)));
      pts.colour.push_back(glm::vec3(0.5f));
      pts.normal.push_back(i % 7 ? glm::vec3(0, 0, 1) : glm::vec3(0));
    }
    buildChecked(pts, opt);
  }
}

// Positions of a scan far from its origin (national-grid metres, had a caller not moved them to
// the node's frame): float rounding must not break containment.
TEST(Bsh, FarFromTheOriginContainmentHolds) {
  BshPoints pts = randomPoints(2000, 4, true, 0.5f);
  for (auto& p : pts.position) p += glm::vec3(500000.f, 5200000.f, 300.f);
  BshOptions opt;
  opt.leafRadius = 0.5f;
  buildChecked(pts, opt);
}

TEST(Bsh, BadPointsAreRejectedAndCountedAndHdrSurvives) {
  BshPoints pts = randomPoints(100, 2, true, 0.2f);
  pts.position[3].x = NAN;
  pts.position[4].y = INFINITY;
  pts.colour[5].g = NAN;
  pts.colour[6].b = -1;
  pts.normal[7] = glm::vec3(NAN);   // unknown normal: kept, its cone bounds nothing
  pts.colour[8] = glm::vec3(1e6f);  // beyond half float's 65504
  BshOptions opt;
  opt.leafRadius = 0.01f;
  const Bsh bsh = buildChecked(pts, opt);
  EXPECT_EQ(bsh.stats.rejected, 4u);
  EXPECT_EQ(bsh.nodes[0].links.z, 96u);
  EXPECT_FLOAT_EQ(bsh.nodes[bsh.leafOf[8]].colour.r, 1e6f);
  EXPECT_FLOAT_EQ(bsh.nodes[bsh.leafOf[7]].colour.w, float(BSH_CONE_NONE));
  EXPECT_GT(bsh.nodes[0].colour.r, 1e6f / 96 * 0.99f);
  // All rejected: no tree.
  BshPoints bad;
  bad.position.assign(10, glm::vec3(NAN));
  bad.colour.assign(10, glm::vec3(1));
  const Bsh none = buildChecked(bad, opt);
  EXPECT_TRUE(none.nodes.empty());
  EXPECT_EQ(none.stats.rejected, 10u);
}

// The top tree over several nodes' roots: every root one leaf (links.y its index), spheres and
// cones of inner nodes containing their children's, counts summed.
TEST(TopTree, JoinsRootsIntoOneHierarchy) {
  std::vector<BshNode> roots;
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> u(0, 1);
  for (int i = 0; i < 300; ++i) {
    BshPoints pts = randomPoints(50, uint32_t(i), true, 0.3f);
    const glm::vec3 offset(u(rng) * 100, u(rng) * 100, u(rng) * 10);
    for (auto& p : pts.position) p = p * 0.1f + offset;
    if (i % 5 == 0)  // flat patches: narrow cones
      for (auto& n : pts.normal) n = glm::normalize(glm::vec3(0.05f * u(rng), 0.05f * u(rng), 1));
    BshOptions opt;
    opt.leafRadius = 0.01f;
    roots.push_back(buildBsh(pts, opt).nodes[0]);
  }
  roots.push_back(roots[7]);  // two nodes with one centre stay two leaves
  const Bsh top = buildTopTree(roots);
  ASSERT_EQ(top.nodes.size(), 2 * roots.size() - 1);
  std::vector<int> seen(roots.size(), 0);
  uint64_t leafCount = 0;
  for (uint32_t i = 0; i < top.nodes.size(); ++i) {
    const BshNode& n = top.nodes[i];
    if (isLeaf(n)) {
      ASSERT_LT(n.links.y, roots.size());
      seen[n.links.y]++;
      const BshNode& r = roots[n.links.y];
      EXPECT_EQ(n.sphere, r.sphere);
      EXPECT_EQ(n.links.w, r.links.w);
      EXPECT_EQ(n.colour.w, r.colour.w);
      leafCount += n.links.z;
      continue;
    }
    const NormalCone cone{coneAxis(n), n.colour.w};
    for (uint32_t ch : {n.links.x, n.links.y}) {
      const BshNode& k = top.nodes[ch];
      EXPECT_LE(glm::length(glm::vec3(k.sphere) - glm::vec3(n.sphere)) + k.sphere.w,
                n.sphere.w * (1 + kSphereRel));
      if (!cone.boundsNothing()) {
        EXPECT_NE(k.links.w, 0u);
        EXPECT_TRUE(cone.contains(NormalCone{coneAxis(k), k.colour.w}, kConeSlack));
      }
    }
    EXPECT_EQ(n.links.z, top.nodes[n.links.x].links.z + top.nodes[n.links.y].links.z);
  }
  for (int s : seen) EXPECT_EQ(s, 1);
  EXPECT_EQ(leafCount, top.nodes[0].links.z);
  EXPECT_TRUE(buildTopTree({}).nodes.empty());
  const Bsh one = buildTopTree({roots[3]});
  ASSERT_EQ(one.nodes.size(), 1u);
  EXPECT_EQ(one.nodes[0].links.y, 0u);
}

}  // namespace
}  // namespace nestlight::gi
