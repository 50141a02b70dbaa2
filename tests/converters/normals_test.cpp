// Plane-fit normals and their depth rule (Rohmer, Jendersie, Grosch, "Natural Environment
// Illumination: Coherent Interactive Augmented Reality for Mobile and non-Mobile Devices", 2017,
// section 5): neighbours more than a depth limit off the point are left out of its plane, so a
// thin wall's two faces do not blur each other's normals.
#include "nestlight/converters/normals.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <random>

#include "nestlight/converters/builder.h"
#include "nestlight/octree/octree_reader.h"
#include "test_support.h"

using namespace nestlight;
namespace fs = std::filesystem;

namespace {

// A thin horizontal wall: points on its two faces, z = 0 and z = 0.3 m, over a 4 m square, each
// face sampled on a 0.4 m grid jittered by up to 0.16 m (a scanner's regular pattern, not exact).
// At this spacing a point's 16 nearest neighbours reach about 0.65 m, beyond the 0.3 m gap, so
// every neighbourhood holds points of both faces (checked below).
struct Wall {
  std::vector<double> xyz;  // metres, on the 1 mm grid
  size_t size() const { return xyz.size() / 3; }
};

constexpr double kGap = 0.3, kSpacing = 0.4;
constexpr int kCells = 10;
constexpr unsigned kNeighbours = 16;

Wall thinWall(uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.4, 0.4);
  Wall w;
  for (int face = 0; face < 2; ++face)
    for (int i = 0; i < kCells; ++i)
      for (int j = 0; j < kCells; ++j) {
        // Whole millimetres: the positions are exact in the octree's 1 mm grid.
        w.xyz.push_back(std::round((i + 0.5 + jitter(rng)) * kSpacing * 1000) / 1000);
        w.xyz.push_back(std::round((j + 0.5 + jitter(rng)) * kSpacing * 1000) / 1000);
        w.xyz.push_back(face * kGap);
      }
  return w;
}

// The fewest neighbours of the other face among a point's k nearest (brute force).
size_t fewestFromTheOtherFace(const Wall& w) {
  size_t fewest = kNeighbours;
  for (size_t i = 0; i < w.size(); ++i) {
    std::vector<std::pair<double, size_t>> d;
    for (size_t j = 0; j < w.size(); ++j) {
      double s = 0;
      for (int a = 0; a < 3; ++a) s += std::pow(w.xyz[3 * j + a] - w.xyz[3 * i + a], 2);
      d.push_back({s, j});
    }
    std::partial_sort(d.begin(), d.begin() + kNeighbours, d.end());
    size_t other = 0;
    for (size_t j = 0; j < kNeighbours; ++j)
      other += w.xyz[3 * d[j].second + 2] != w.xyz[3 * i + 2];
    fewest = std::min(fewest, other);
  }
  return fewest;
}

// How far normals lie from the faces' normal, +-z: the largest angle and how many exceed 1 degree.
struct Tilt {
  double worstDegrees = 0;
  size_t overOneDegree = 0;
};

Tilt tilt(const float* normals, size_t n) {
  Tilt t;
  for (size_t i = 0; i < n; ++i) {
    const float* m = normals + 3 * i;
    const double len = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    EXPECT_NEAR(len, 1.0, 1e-5) << "point " << i << " has no normal";
    const double degrees = std::acos(std::min(1.0, std::abs(m[2]) / len)) * 180 / M_PI;
    t.worstDegrees = std::max(t.worstDegrees, degrees);
    t.overOneDegree += degrees > 1;
  }
  return t;
}

std::vector<float> estimate(const Wall& w, double depthLimitMm) {
  std::vector<uint32_t> pos(w.xyz.size());
  for (size_t i = 0; i < pos.size(); ++i) pos[i] = uint32_t(std::lround(w.xyz[i] * 1000));
  std::vector<float> normals(pos.size());
  const double centre[3] = {0, 0, 0};
  estimateNormals(pos.data(), w.size(), kNeighbours, 2, centre, normals.data(), depthLimitMm);
  return normals;
}

}  // namespace

TEST(Normals, DepthRuleKeepsAThinWallsFacesApart) {
  const Wall w = thinWall(7);
  ASSERT_GE(fewestFromTheOtherFace(w), 3u) << "the faces do not mix: the test tests nothing";
  // Without the rule a point's plane is fitted across both faces: it tilts towards wherever the
  // far face's neighbours happen to lie, at nearly every point.
  const Tilt without = tilt(estimate(w, 0).data(), w.size());
  EXPECT_GT(without.worstDegrees, 5.0);
  EXPECT_GT(without.overOneDegree, w.size() / 2);
  // With it (0.1 m, the paper's) each face's points alone are fitted, and points of one face are
  // exactly coplanar: only float rounding is left, far inside a degree.
  const Tilt with = tilt(estimate(w, 100).data(), w.size());
  EXPECT_LT(with.worstDegrees, 1.0);
  EXPECT_EQ(with.overOneDegree, 0u);
  // A limit wider than the gap keeps both faces, as no limit does.
  EXPECT_GT(tilt(estimate(w, 400).data(), w.size()).overOneDegree, w.size() / 2);
}

// Through the converter: the limit is given in world units (metres) and applied in the octree's
// integer grid, and the metadata records it.
TEST(Normals, ConverterAppliesTheLimitInWorldUnits) {
  test::TempDir tmp;
  const Wall w = thinWall(11);
  {
    std::ofstream f(tmp.file("wall.xyz"));
    f.precision(10);
    for (size_t i = 0; i < w.size(); ++i)
      f << w.xyz[3 * i] << ' ' << w.xyz[3 * i + 1] << ' ' << w.xyz[3 * i + 2] << '\n';
  }
  auto tiltAfterBuild = [&](double limit, const std::string& name) {
    BuildOptions o;
    o.output = tmp.path() / name;
    o.progress = ProgressMode::Quiet;
    o.threads = 2;
    o.normalNeighbours = kNeighbours;
    o.precision = 0.001;
    o.estimateNormals = true;
    o.normalOrientation = NormalOrientation::Up;
    o.normalDepthLimit = limit;
    std::vector<std::unique_ptr<PointReader>> src;
    src.push_back(openReader(tmp.file("wall.xyz")));
    buildOctree(std::move(src), o);
    OctreeReader reader(o.output);
    EXPECT_EQ(reader.metadata().normalEstimation.value("depth_limit", -1.0), limit);
    const int ni = reader.metadata().layout.find("normal");
    EXPECT_GE(ni, 0);
    const size_t off = reader.metadata().layout.offset(size_t(ni));
    std::vector<float> normals;
    for (auto& [k, e] : reader.allNodes()) {
      PointBuffer p = reader.readNode(k);
      for (size_t i = 0; i < p.size(); ++i) {
        float n[3];
        std::memcpy(n, p.attrsOf(i) + off, 12);
        normals.insert(normals.end(), n, n + 3);
      }
    }
    EXPECT_EQ(normals.size(), w.xyz.size());
    return tilt(normals.data(), normals.size() / 3);
  };
  EXPECT_GT(tiltAfterBuild(0, "off").overOneDegree, w.size() / 2);
  const Tilt with = tiltAfterBuild(0.1, "on");
  EXPECT_LT(with.worstDegrees, 1.0);
  EXPECT_EQ(with.overOneDegree, 0u);
}
