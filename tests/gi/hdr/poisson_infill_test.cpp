// Gradient-domain HDR in-fill on a point cloud's k-nearest-neighbour graph (Sabbadin, Palma,
// Banterle, Boubekeur, Cignoni, "High Dynamic Range Point Clouds for Real-Time Relighting", 2019,
// section 4.2, eq. 3; after Pérez, Gangnet, Blake, "Poisson Image Editing", 2003): properties the
// solution must have exactly, up to the conjugate-gradient tolerance and float rounding.
//
// Tolerances: CG stops at |b - A x| <= tol |b|, which bounds the error by tol |b| / lambda_min(A)
// in the 2-norm (so in every entry too). The tests run with tol = 1e-12; each states |b| and
// lambda_min where it matters. On top of that the result is stored as float, half an ulp:
// 2^-24 (6e-8) of the value.
#include "nestlight/gi/hdr/poisson_infill.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace nestlight::gi::hdr {
namespace {

struct Cloud {
  std::vector<glm::vec3> position, ldr, hdr;
  std::vector<InfillRole> role;

  size_t add(glm::vec3 p, glm::vec3 l, glm::vec3 h, InfillRole r) {
    position.push_back(p);
    ldr.push_back(l);
    hdr.push_back(h);
    role.push_back(r);
    return position.size() - 1;
  }
  InfillStats infill(const InfillOptions& options) {
    return poissonInfill(position, ldr, hdr, role, options);
  }
};

InfillOptions tight(int k = 16) {
  InfillOptions o;
  o.k = k;
  o.tolerance = 1e-12;
  o.maxIterations = 10000;
  return o;
}

// A smooth colour over space, each channel different, all positive.
glm::vec3 smoothColour(const glm::vec3& p) {
  return {0.5f + 0.4f * std::sin(3.0f * p.x + 1.0f * p.y), 0.4f + 0.3f * std::cos(2.0f * p.y - p.z),
          0.3f + 0.25f * std::sin(4.0f * p.x * p.y + 2.0f * p.z)};
}

// Points on a wavy sheet over [0, 1]^2.
glm::vec3 sheetPoint(std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float x = u(rng), y = u(rng);
  return {x, y, 0.1f * std::sin(6.0f * x) * std::cos(5.0f * y)};
}

float maxAbsDifference(const glm::vec3& a, const glm::vec3& b) {
  return std::max({std::abs(a.x - b.x), std::abs(a.y - b.y), std::abs(a.z - b.z)});
}

// 40 x 40 grid, z = 0, spacing 1: with k = 12 an interior point's neighbours are the 12 at
// distances 1, sqrt 2 and 2 (the 13th is at sqrt 5: no tie). h = x^2 - y^2 + 3x - 2y is
// discrete-harmonic for that stencil: h(p + d) - h(p) = grad h . d + dx^2 - dy^2, and summed over
// the stencil the linear term cancels (the stencil is symmetric under d -> -d) and so does the
// quadratic one (symmetric under swapping x and y). With L = 0 there is no guidance, so the
// solution is the discrete-harmonic extension of the boundary: h itself.
//
// Near the grid's border a point's stencil is truncated and its kNN reaches further (to sqrt 5
// along an edge, sqrt 10 at a corner, with ties at sqrt 5), so through the symmetrised graph it
// can add edges to points up to three rows in. Those rows must be fixed; the premise is checked
// below by brute force, independently of how the tree breaks ties (a fixed ring 3 wide fails it).
TEST(PoissonInfill, HarmonicFunctionOnAGridIsReproduced) {
  constexpr int kN = 40, kRing = 4, kK = 12;
  // Centred, and lifted by 1000 so that it stays positive (negative results are clamped): values
  // in [500, 1500], integers, exact in float.
  const auto h = [](int x, int y, double lift = 1000) {
    const double u = x - 20, v = y - 20;
    return float(u * u - v * v + 3 * u - 2 * v + lift);
  };
  Cloud cloud;
  for (int x = 0; x < kN; ++x) {
    for (int y = 0; y < kN; ++y) {
      const int border = std::min({x, y, kN - 1 - x, kN - 1 - y});
      const bool target = border >= kRing;
      cloud.add({float(x), float(y), 0.0f}, glm::vec3(0.0f),
                target ? glm::vec3(-7.0f) : glm::vec3(h(x, y)),
                target ? InfillRole::Target : InfillRole::Fixed);
    }
  }

  // The premise: every target has exactly the 12-stencil as its symmetrised neighbourhood. Its
  // own 12 nearest are the stencil without a tie, and no point q off its stencil could have it
  // among q's 12 nearest (it is farther from q than q's 12th nearest, whatever the tie-breaking).
  const size_t n = cloud.position.size();
  std::vector<float> twelfth(n), thirteenth(n);
  for (size_t p = 0; p < n; ++p) {
    std::vector<float> d;
    for (size_t q = 0; q < n; ++q) {
      if (q == p) continue;
      const glm::vec3 e = cloud.position[p] - cloud.position[q];
      d.push_back(e.x * e.x + e.y * e.y);
    }
    std::nth_element(d.begin(), d.begin() + kK, d.end());
    thirteenth[p] = d[kK];
    std::nth_element(d.begin(), d.begin() + kK - 1, d.begin() + kK);
    twelfth[p] = d[kK - 1];
  }
  for (size_t p = 0; p < n; ++p) {
    if (cloud.role[p] != InfillRole::Target) continue;
    ASSERT_EQ(twelfth[p], 4.0f);
    ASSERT_EQ(thirteenth[p], 5.0f);
    for (size_t q = 0; q < n; ++q) {
      const glm::vec3 e = cloud.position[p] - cloud.position[q];
      const float d = e.x * e.x + e.y * e.y;
      if (q != p && d > 4.0f) {
        ASSERT_GT(d, twelfth[q]) << p << " " << q;
      }
    }
  }

  for (InfillPreconditioner pre :
       {InfillPreconditioner::IncompleteCholesky, InfillPreconditioner::Diagonal}) {
    Cloud c = cloud;
    InfillOptions o = tight(kK);
    o.preconditioner = pre;
    const InfillStats s = c.infill(o);
    EXPECT_EQ(s.targets, 32u * 32u);
    EXPECT_EQ(s.solved, 32u * 32u);
    EXPECT_EQ(s.islands, 0u);
    EXPECT_TRUE(s.converged);
    EXPECT_LE(s.cgError, 1e-12);
    EXPECT_GT(s.cgIterations, 0u);
    EXPECT_EQ(s.clampedNegative, 0u);
    // |b| <= sqrt(1024 rows) * 12 neighbours * 1500 ~ 6e5; lambda_min of the Dirichlet 12-stencil
    // Laplacian on 32 x 32 is about 7 (its second moment) * 2 pi^2 / 33^2 ~ 0.13: the CG error is
    // below 5e-6. Float rounding of values up to 1500 adds 6e-5.
    float worst = 0;
    for (int x = 0; x < kN; ++x)
      for (int y = 0; y < kN; ++y)
        worst = std::max(worst, maxAbsDifference(c.hdr[size_t(x * kN + y)], glm::vec3(h(x, y))));
    EXPECT_LE(worst, 1e-4f);
  }

  // Unlifted, h is negative over part of the hole: those targets are clamped to 0 and counted
  // (h is an integer there, so only its zeros are at the mercy of rounding).
  for (int x = 0; x < kN; ++x)
    for (int y = 0; y < kN; ++y)
      if (cloud.role[size_t(x * kN + y)] == InfillRole::Fixed)
        cloud.hdr[size_t(x * kN + y)] = glm::vec3(h(x, y, 0));
  const InfillStats s = cloud.infill(tight(kK));
  uint64_t negative = 0, zero = 0;
  for (int x = 0; x < kN; ++x) {
    for (int y = 0; y < kN; ++y) {
      const size_t i = size_t(x * kN + y);
      if (cloud.role[i] != InfillRole::Target) continue;
      const float expected = h(x, y, 0);
      negative += expected < 0;
      zero += expected == 0;
      EXPECT_LE(maxAbsDifference(cloud.hdr[i], glm::vec3(std::max(expected, 0.0f))), 1e-4f);
    }
  }
  EXPECT_GT(negative, 100u);
  EXPECT_GE(s.clampedNegative, negative);
  EXPECT_LE(s.clampedNegative, negative + zero);
}

// With H = L on the valid points, H = L is the solution whatever L is: each row's gradient term
// sum (L(p) - L(q)) is exactly what A L leaves over the boundary. Shown for a smooth L and for
// white noise, with targets scattered (30%) among the valid points on a curved sheet.
TEST(PoissonInfill, GradientsDetermineTheSolution) {
  for (bool noise : {false, true}) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    Cloud cloud;
    for (int i = 0; i < 5000; ++i) {
      const glm::vec3 p = sheetPoint(rng);
      const glm::vec3 f = noise ? glm::vec3(u(rng), u(rng), u(rng)) : smoothColour(p);
      const bool target = u(rng) < 0.3f;
      cloud.add(p, f, target ? glm::vec3(0.0f) : f,
                target ? InfillRole::Target : InfillRole::Fixed);
    }
    const InfillStats s = cloud.infill(tight());
    EXPECT_GT(s.targets, 1300u);
    EXPECT_EQ(s.solved, s.targets);
    EXPECT_EQ(s.islands, 0u);
    EXPECT_TRUE(s.converged);
    // |b| <= sqrt(1500 rows) * 2 * 32 (twice a row's degree, symmetrised) * 1 ~ 2.5e3. By
    // Gershgorin (A is symmetric, its row p has the degree on the diagonal and -1 per target
    // neighbour) lambda_min >= the fewest valid neighbours any target has: at least 1 here, as a
    // target with none among its 16 nearest has probability 0.3^16. The CG error is below 3e-9;
    // the float result adds 6e-8.
    float worst = 0;
    for (size_t i = 0; i < cloud.position.size(); ++i)
      worst = std::max(worst, maxAbsDifference(cloud.hdr[i], cloud.ldr[i]));
    EXPECT_LE(worst, 1e-6f) << "noise " << noise;
  }
}

// The system sees gradients only, so a constant offset on the boundary carries into the hole:
// H = L + c on the valid points gives L + c on the targets, here a clustered hole (a disc of
// radius 0.25) where the solve has real work to do, a different c per channel, and half the
// valid points playing the guides of an out-of-core chunk (FixedGuide must act as Fixed).
TEST(PoissonInfill, ConstantOffsetCarriesIntoTheHole) {
  const glm::vec3 c(0.75f, -0.125f, 2.5f);
  std::mt19937 rng(5);
  Cloud cloud;
  for (int i = 0; i < 6000; ++i) {
    const glm::vec3 p = sheetPoint(rng);
    const glm::vec3 l = smoothColour(p);
    const float dx = p.x - 0.5f, dy = p.y - 0.5f;
    const bool target = dx * dx + dy * dy < 0.25f * 0.25f;
    cloud.add(p, l, target ? glm::vec3(0.0f) : l + c,
              target ? InfillRole::Target : (i % 2 ? InfillRole::Fixed : InfillRole::FixedGuide));
  }
  for (InfillPreconditioner pre :
       {InfillPreconditioner::IncompleteCholesky, InfillPreconditioner::Diagonal}) {
    Cloud run = cloud;
    InfillOptions o = tight();
    o.preconditioner = pre;
    const InfillStats s = run.infill(o);
    EXPECT_GT(s.solved, 1000u);
    EXPECT_EQ(s.solved, s.targets);
    EXPECT_EQ(s.islands, 0u);
    EXPECT_EQ(s.clampedNegative, 0u);  // L - 0.125 stays positive: L.g >= 0.1
    EXPECT_TRUE(s.converged);
    // |b| <= sqrt(1200) * 32 * 3 ~ 3.3e3; lambda_min for a hole about 25 neighbour spacings
    // across is of order 16 * 2 pi^2 / 25^2 / 4 ~ 0.1: CG error below 4e-8; floats add 2e-7.
    float worst = 0;
    for (size_t i = 0; i < run.position.size(); ++i)
      if (run.role[i] == InfillRole::Target)
        worst = std::max(worst, maxAbsDifference(run.hdr[i], run.ldr[i] + c));
    EXPECT_LE(worst, 2e-6f);
  }
}

// A group of targets that no valid point touches has nothing to anchor it: it is found before the
// solve, counted, and given L (or islandScale * L), and the rest still solves.
TEST(PoissonInfill, IslandsAreDetectedAndGivenTheirLdrColour) {
  const glm::vec3 c(1.0f, 2.0f, 3.0f);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  Cloud cloud;
  for (int i = 0; i < 3000; ++i) {
    const glm::vec3 p = sheetPoint(rng);
    const bool target = p.x < 0.3f && p.y < 0.3f;
    cloud.add(p, smoothColour(p), smoothColour(p) + c,
              target ? InfillRole::Target : InfillRole::Fixed);
  }
  // 50 targets in a ball of radius 0.05 a thousand units away.
  std::vector<size_t> island;
  for (int i = 0; i < 50; ++i) {
    const glm::vec3 p = glm::vec3(1000.0f) + 0.05f * glm::vec3(u(rng), u(rng), u(rng));
    island.push_back(cloud.add(p, smoothColour(p), glm::vec3(NAN), InfillRole::Target));
  }
  for (float scale : {1.0f, 2.5f}) {
    Cloud run = cloud;
    InfillOptions o = tight();
    o.islandScale = scale;
    const InfillStats s = run.infill(o);
    EXPECT_EQ(s.islands, 1u);
    EXPECT_EQ(s.islandPoints, 50u);
    EXPECT_EQ(s.solved + s.islandPoints, s.targets);
    EXPECT_GT(s.solved, 100u);
    for (size_t i : island) EXPECT_EQ(run.hdr[i], scale * run.ldr[i]);
    float worst = 0;
    for (size_t i = 0; i < 3000; ++i)
      worst = std::max(worst, maxAbsDifference(run.hdr[i], run.ldr[i] + c));
    EXPECT_LE(worst, 2e-6f);  // as in ConstantOffsetCarriesIntoTheHole
  }

  // No valid point at all: two far-apart groups, both islands, nothing solved, nothing NaN.
  Cloud none;
  for (int i = 0; i < 200; ++i) {
    const glm::vec3 p = glm::vec3(i < 100 ? 0.0f : 50.0f) + glm::vec3(u(rng), u(rng), u(rng));
    none.add(p, smoothColour(p), glm::vec3(NAN), InfillRole::Target);
  }
  const InfillStats s = none.infill(tight());
  EXPECT_EQ(s.targets, 200u);
  EXPECT_EQ(s.islands, 2u);
  EXPECT_EQ(s.islandPoints, 200u);
  EXPECT_EQ(s.solved, 0u);
  for (size_t i = 0; i < none.position.size(); ++i) EXPECT_EQ(none.hdr[i], none.ldr[i]);
}

// Luminance mode solves for Y(H) with Y(L)'s gradients and gives H the chromaticity of L: the
// ratio H / L is the same in every channel. Built so the luminance has an exact answer too: with
// Y(H) = Y(L) + c on the valid points, Y(H) = Y(L) + c on the targets (as in the offset test).
// Black targets (Y(L) = 0) have no chromaticity to keep and come out grey, at Y(H) = c.
TEST(PoissonInfill, LuminanceModeKeepsLdrChromaticity) {
  constexpr double kC = 1.5;
  std::mt19937 rng(9);
  Cloud cloud;
  std::vector<size_t> black;
  for (int i = 0; i < 5000; ++i) {
    const glm::vec3 p = sheetPoint(rng);
    const glm::vec3 l = smoothColour(p);
    const double y = infillLuminance(l);
    const float dx = p.x - 0.4f, dy = p.y - 0.6f;
    const bool target = dx * dx + dy * dy < 0.2f * 0.2f;
    cloud.add(p, l, target ? glm::vec3(0.0f) : l * float((y + kC) / y),
              target ? InfillRole::Target : InfillRole::Fixed);
  }
  // Black targets at the hole's centre.
  for (int i = 0; i < 3; ++i)
    black.push_back(cloud.add({0.4f + 0.001f * float(i), 0.6f, 0.0f}, glm::vec3(0.0f),
                              glm::vec3(0.0f), InfillRole::Target));

  InfillOptions o = tight();
  o.mode = InfillMode::Luminance;
  const InfillStats s = cloud.infill(o);
  EXPECT_GT(s.solved, 500u);
  EXPECT_EQ(s.islands, 0u);
  EXPECT_TRUE(s.converged);
  size_t checked = 0;
  for (size_t i = 0; i < cloud.position.size(); ++i) {
    if (cloud.role[i] != InfillRole::Target) continue;
    const glm::vec3 h = cloud.hdr[i], l = cloud.ldr[i];
    if (std::find(black.begin(), black.end(), i) != black.end()) {
      EXPECT_EQ(h.x, h.y);
      EXPECT_EQ(h.y, h.z);
      EXPECT_NEAR(h.x, kC, 1e-6);  // Y(L) + c with Y(L) = 0
      continue;
    }
    // The ratios agree to float rounding of H (each a few ulps: 1e-6 relative). The luminance
    // agrees with Y(L) + c to the CG error (|b| <= sqrt(1300) * 32 * 2 ~ 2.3e3 times 1e-12 over
    // lambda_min ~ 0.1: below 3e-8), plus the float rounding of the valid points' H (which the
    // solution, an average of the boundary, cannot amplify) and of the targets' H: each 2^-24 of
    // values up to 4, 2.4e-7.
    const float rr = h.x / l.x, rg = h.y / l.y, rb = h.z / l.z;
    EXPECT_NEAR(rg / rr, 1.0f, 1e-6f);
    EXPECT_NEAR(rb / rr, 1.0f, 1e-6f);
    EXPECT_NEAR(infillLuminance(h), infillLuminance(l) + kC, 1e-6);
    EXPECT_GT(rr, 2.0f);  // far from 1: the test is not vacuous
    checked++;
  }
  EXPECT_GT(checked, 500u);
}

// Coincident points are neighbours at distance 0 (more of them than k, so the query point itself
// is not necessarily the first found), and points with non-finite coordinates or colours are left
// out of the graph, counted, and never spread NaN.
TEST(PoissonInfill, CoincidentPointsAndNonFiniteInputs) {
  const glm::vec3 c(0.5f, 0.25f, 1.0f);
  std::mt19937 rng(13);
  Cloud cloud;
  for (int i = 0; i < 3000; ++i) {
    const glm::vec3 p = sheetPoint(rng);
    cloud.add(p, smoothColour(p), smoothColour(p) + c, InfillRole::Fixed);
  }
  // 100 targets on the position of a valid point: their own 16 nearest are each other, and only
  // the symmetrised graph links them to the valid points that count them among their nearest.
  const glm::vec3 at = cloud.position[17];
  std::vector<size_t> stacked;
  for (int i = 0; i < 100; ++i)
    stacked.push_back(cloud.add(at, smoothColour(at), glm::vec3(NAN), InfillRole::Target));
  // 100 valid points stacked elsewhere, and a target next to them.
  const glm::vec3 at2 = cloud.position[1234];
  for (int i = 0; i < 100; ++i)
    cloud.add(at2, smoothColour(at2), smoothColour(at2) + c, InfillRole::Fixed);
  const glm::vec3 near2 = at2 + glm::vec3(1e-3f, 0.0f, 0.0f);
  const size_t nextToStack =
      cloud.add(near2, smoothColour(near2), glm::vec3(0.0f), InfillRole::Target);
  // 100 stacked targets far from everything: an island.
  std::vector<size_t> island;
  for (int i = 0; i < 100; ++i)
    island.push_back(
        cloud.add(glm::vec3(-500.0f), glm::vec3(0.25f), glm::vec3(0.0f), InfillRole::Target));
  // Non-finite inputs: positions (target and valid), an LDR colour, a valid HDR colour.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const size_t nanTarget =
      cloud.add({nan, 0.5f, 0.0f}, glm::vec3(0.3f), glm::vec3(0.0f), InfillRole::Target);
  const size_t infLdrTarget = cloud.add({0.5f, 0.5f, 0.0f}, glm::vec3(inf, 0.1f, 0.1f),
                                        glm::vec3(0.0f), InfillRole::Target);
  cloud.add({0.5f, nan, 0.0f}, glm::vec3(0.3f), glm::vec3(0.3f), InfillRole::Fixed);
  cloud.add({0.5f, 0.5f, 0.0f}, glm::vec3(0.3f), glm::vec3(nan), InfillRole::Fixed);
  cloud.add({0.5f, 0.5f, 0.0f}, glm::vec3(nan), glm::vec3(1.0f), InfillRole::FixedGuide);
  cloud.add({inf, inf, inf}, glm::vec3(0.3f), glm::vec3(0.3f), InfillRole::Fixed);

  for (InfillMode mode : {InfillMode::Rgb, InfillMode::Luminance}) {
    Cloud run = cloud;
    InfillOptions o = tight();
    o.mode = mode;
    const InfillStats s = run.infill(o);
    EXPECT_EQ(s.nonFiniteInputs, 6u);
    EXPECT_EQ(s.excludedTargets, 2u);
    EXPECT_EQ(s.targets, 100u + 1u + 100u + 2u);
    EXPECT_EQ(s.islands, 1u);
    EXPECT_EQ(s.islandPoints, 100u);
    EXPECT_EQ(s.solved, 101u);
    EXPECT_EQ(s.nonFiniteResults, 0u);
    for (const glm::vec3& h : run.hdr)
      if (&h - run.hdr.data() != std::ptrdiff_t(cloud.position.size()) - 3) {  // the NaN input
        EXPECT_TRUE(std::isfinite(h.x) && std::isfinite(h.y) && std::isfinite(h.z));
      }
    EXPECT_EQ(run.hdr[nanTarget], glm::vec3(0.3f));
    EXPECT_EQ(run.hdr[infLdrTarget], glm::vec3(0.0f));
    for (size_t i : island) EXPECT_EQ(run.hdr[i], glm::vec3(0.25f));
    if (mode == InfillMode::Rgb) {
      // The offset carries exactly (see ConstantOffsetCarriesIntoTheHole).
      for (size_t i : stacked) EXPECT_LE(maxAbsDifference(run.hdr[i], run.ldr[i] + c), 2e-6f);
      EXPECT_LE(maxAbsDifference(run.hdr[nextToStack], run.ldr[nextToStack] + c), 2e-6f);
    }
  }
}

TEST(PoissonInfill, RejectsMismatchedInputs) {
  std::vector<glm::vec3> p(3), l(3), h(2);
  std::vector<InfillRole> r(3, InfillRole::Target);
  EXPECT_THROW(poissonInfill(p, l, h, r), std::invalid_argument);
  h.resize(3);
  InfillOptions o;
  o.k = 0;
  EXPECT_THROW(poissonInfill(p, l, h, r, o), std::invalid_argument);
  const InfillStats s = poissonInfill(p, l, h, r);  // three coincident targets: one island
  EXPECT_EQ(s.islands, 1u);
  EXPECT_EQ(s.islandPoints, 3u);
}

}  // namespace
}  // namespace nestlight::gi::hdr
