// Meshes sampled into surfels: areas that sum to the mesh's area, area-uniform density across
// triangles of very different size (chi-square), the Poisson-disk spacing, normals under
// non-uniform scale and mirroring, vertex colours times the base colour, determinism per seed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>
#include <string>
#include <vector>

#include "nestlight/gi/mesh.h"
#include "test_support.h"

using namespace nestlight::gi;

namespace {

// The unit square in z = 0, cut into triangles of very different size: a fan from (0,0) to the
// top edge at x = t^3 (slivers near x = 0, wide ones near x = 1), and one half of the square.
TriangleMesh irregularSquare() {
  TriangleMesh m;
  m.positions.push_back({0, 0, 0});
  m.positions.push_back({1, 0, 0});
  const int steps = 20;
  for (int i = 0; i <= steps; ++i) {
    const float t = float(i) / steps;
    m.positions.push_back({t * t * t, 1, 0});
  }
  for (int i = 0; i < steps; ++i)
    m.indices.insert(m.indices.end(), {0, uint32_t(i + 3), uint32_t(i + 2)});
  m.indices.insert(m.indices.end(), {0, 1, uint32_t(steps + 2)});
  return m;
}

// Nearest-neighbour distance of each point, by brute force.
std::vector<double> nearest(const std::vector<glm::vec3>& p) {
  std::vector<double> d(p.size(), INFINITY);
  for (size_t i = 0; i < p.size(); ++i)
    for (size_t j = i + 1; j < p.size(); ++j) {
      const double x = glm::distance(glm::dvec3(p[i]), glm::dvec3(p[j]));
      d[i] = std::min(d[i], x), d[j] = std::min(d[j], x);
    }
  return d;
}

std::string bunnyPath() {
  const std::string p = (::nestlight::test::sharedData() / "meshes" / "bunny.ply").string();
  return std::filesystem::exists(p) ? p : std::string();
}

TEST(MeshSampling, MeshAreaUnderAnAffineTransform) {
  TriangleMesh square = irregularSquare();
  EXPECT_NEAR(meshArea(square, glm::mat4(1)), 1.0, 1e-6);
  glm::mat4 m = glm::translate(glm::mat4(1), glm::vec3(100, -5, 3));
  m = glm::rotate(m, 0.6f, glm::vec3(1, 2, 3));
  m = glm::scale(m, glm::vec3(2, 3, 5));
  // 1e-5: float rotation matrices are orthonormal to about 1e-7.
  EXPECT_NEAR(meshArea(square, m), 6.0, 1e-5);
  // A transform that flattens the square onto a line leaves no area and no points.
  const glm::mat4 flat = glm::scale(glm::mat4(1), glm::vec3(1, 0, 1));
  EXPECT_EQ(meshArea(square, flat), 0.0);
  EXPECT_TRUE(sampleSurfels(square, flat, {}).positions.empty());
}

TEST(MeshSampling, SurfelAreasSumToTheMeshArea) {
  std::vector<std::pair<std::string, TriangleMesh>> meshes = {
      {"irregular square", irregularSquare()}};
  if (const std::string p = bunnyPath(); !p.empty()) meshes.push_back({"bunny", readMesh(p)});
  const glm::mat4 m =
      glm::scale(glm::rotate(glm::mat4(1), 1.0f, glm::vec3(0, 1, 1)), glm::vec3(3, 1, 0.5f));
  for (const auto& [name, mesh] : meshes)
    for (auto method : {SurfelSampling::AreaUniform, SurfelSampling::PoissonDisk}) {
      SCOPED_TRACE(name + (method == SurfelSampling::PoissonDisk ? " Poisson" : " uniform"));
      SurfelOptions o;
      o.method = method;
      o.count = 3000;
      o.material = 7;
      const Surfels s = sampleSurfels(mesh, m, o);
      ASSERT_EQ(s.positions.size(), o.count);  // both methods return exactly `count`
      ASSERT_EQ(s.normals.size(), o.count);
      ASSERT_EQ(s.area.size(), o.count);
      ASSERT_EQ(s.albedo.size(), o.count);
      ASSERT_EQ(s.material, std::vector<uint32_t>(o.count, 7));
      double sum = 0;
      for (float a : s.area) sum += a;
      // Each area is the float nearest total / count: relative error below 2^-24 each.
      const double area = meshArea(mesh, m);
      EXPECT_NEAR(sum, area, 1e-6 * area);
    }
}

// Four disjoint right triangles of areas 1, 10, 100 and 1000, each cut into its four midpoint
// sub-triangles: the 16 counts of area-uniform points must fit area / total.
TEST(MeshSampling, AreaUniformDensityIsUniformAcrossTrianglesOfVeryDifferentSizes) {
  TriangleMesh m;
  const double areas[4] = {1, 10, 100, 1000};
  std::vector<float> legs;
  for (int t = 0; t < 4; ++t) {
    const float a = float(std::sqrt(2 * areas[t]));
    legs.push_back(a);
    const float z = float(t);  // one plane per triangle, to tell them apart
    const auto base = uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), {{0, 0, z}, {a, 0, z}, {0, a, z}});
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2});
  }
  SurfelOptions o;
  o.count = 200000;
  o.seed = 42;
  const Surfels s = sampleSurfels(m, glm::mat4(1), o);
  ASSERT_EQ(s.positions.size(), o.count);
  std::vector<double> count(16, 0);
  for (const glm::vec3& p : s.positions) {
    const int t = int(std::lround(p.z));
    ASSERT_TRUE(t >= 0 && t < 4 && p.z == float(t));
    const double b1 = p.x / legs[t], b2 = p.y / legs[t], b0 = 1 - b1 - b2;
    ASSERT_GE(std::min({b0, b1, b2}), -1e-6) << "a point outside its triangle";
    const int sub = b0 > 0.5 ? 0 : b1 > 0.5 ? 1 : b2 > 0.5 ? 2 : 3;
    count[4 * t + sub] += 1;
  }
  double chi2 = 0;
  for (int t = 0; t < 4; ++t)
    for (int k = 0; k < 4; ++k) {
      const double expect = double(o.count) * areas[t] / 1111.0 / 4;  // 45 in the smallest bin
      chi2 += (count[4 * t + k] - expect) * (count[4 * t + k] - expect) / expect;
    }
  // 15 degrees of freedom: chi2 > 56.5 happens by chance with p < 1e-6.
  EXPECT_LT(chi2, 56.5);
}

// Poisson-disk points keep apart: on the unit square, with r_max = sqrt(A / (2 sqrt(3) N)) the
// radius of N disks in hexagonal packing (so 2 r_max is the largest possible spacing), weighted
// sample elimination from 5N candidates gave nearest distances of at least 1.39 r_max over these
// seeds; 1.25 r_max leaves a margin, and area-uniform points fail it by far (0.005 to 0.2 r_max).
TEST(MeshSampling, PoissonDiskKeepsAMinimumDistanceAndTheCount) {
  const TriangleMesh square = irregularSquare();
  for (uint64_t seed : {1, 2, 3}) {
    SurfelOptions o;
    o.method = SurfelSampling::PoissonDisk;
    o.count = 2000;
    o.seed = seed;
    const Surfels pd = sampleSurfels(square, glm::mat4(1), o);
    ASSERT_EQ(pd.positions.size(), o.count);
    const double rMax = std::sqrt(1.0 / (2 * std::sqrt(3.0) * double(o.count)));
    const auto d = nearest(pd.positions);
    EXPECT_GE(*std::min_element(d.begin(), d.end()), 1.25 * rMax) << "seed " << seed;
    // And no holes: every cell of a 10 x 10 grid holds close to its 20 points.
    std::vector<int> cells(100, 0);
    for (const auto& p : pd.positions)
      cells[std::min(9, int(p.x * 10)) * 10 + std::min(9, int(p.y * 10))]++;
    EXPECT_GE(*std::min_element(cells.begin(), cells.end()), 12) << "seed " << seed;
    EXPECT_LE(*std::max_element(cells.begin(), cells.end()), 28) << "seed " << seed;

    o.method = SurfelSampling::AreaUniform;
    const auto du = nearest(sampleSurfels(square, glm::mat4(1), o).positions);
    EXPECT_LT(*std::min_element(du.begin(), du.end()), 1.25 * rMax) << "the bound has no teeth";
  }
}

// Triangles with unshared vertices whose normals are their face normals, under a rotation and
// the scale (1, 7, 0.2): the surfel normals must be perpendicular to the transformed triangles,
// on the front side, both through the vertex normals and through the face normal.
TEST(MeshSampling, NormalsStayPerpendicularUnderNonUniformScale) {
  Rng rng(9);
  TriangleMesh withNormals;
  for (int t = 0; t < 50; ++t) {
    glm::vec3 p[3];
    for (auto& q : p) q = glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) * 2.0f - 1.0f;
    const glm::vec3 n = glm::normalize(glm::cross(p[1] - p[0], p[2] - p[0]));
    for (const auto& q : p) {
      withNormals.indices.push_back(uint32_t(withNormals.positions.size()));
      withNormals.positions.push_back(q);
      withNormals.normals.push_back(n);
    }
  }
  TriangleMesh faceOnly = withNormals;
  faceOnly.normals.clear();
  glm::mat4 m = glm::translate(glm::mat4(1), glm::vec3(4, 5, 6));
  m = glm::rotate(m, 0.9f, glm::vec3(1, -2, 0.5f));
  m = glm::scale(m, glm::vec3(1, 7, 0.2f));
  const glm::mat3 linear(m);
  bool naiveWouldFail = false;
  for (const TriangleMesh* mesh : {&withNormals, &faceOnly})
    for (size_t t = 0; t < mesh->triangles(); ++t) {
      TriangleMesh one;
      for (int k = 0; k < 3; ++k) {
        one.positions.push_back(mesh->positions[3 * t + k]);
        if (!mesh->normals.empty()) one.normals.push_back(mesh->normals[3 * t + k]);
        one.indices.push_back(uint32_t(k));
      }
      const glm::vec3 w0 = glm::vec3(m * glm::vec4(one.positions[0], 1));
      const glm::vec3 w1 = glm::vec3(m * glm::vec4(one.positions[1], 1));
      const glm::vec3 w2 = glm::vec3(m * glm::vec4(one.positions[2], 1));
      const glm::vec3 e[3] = {glm::normalize(w1 - w0), glm::normalize(w2 - w0),
                              glm::normalize(w2 - w1)};
      const glm::vec3 front = glm::cross(w1 - w0, w2 - w0);  // det > 0: winding keeps its side
      SurfelOptions o;
      o.count = 8;
      o.seed = t;
      const Surfels s = sampleSurfels(one, m, o);
      for (const glm::vec3& n : s.normals) {
        EXPECT_NEAR(glm::length(n), 1, 1e-6);
        // 2e-5: float edges of triangles stretched 35:1 carry a few 1e-6 of relative error.
        for (const auto& edge : e) EXPECT_NEAR(glm::dot(n, edge), 0, 2e-5) << "triangle " << t;
        EXPECT_GT(glm::dot(n, front), 0);
      }
      if (!one.normals.empty()) {
        const glm::vec3 naive = glm::normalize(linear * one.normals[0]);
        naiveWouldFail |= std::abs(glm::dot(naive, e[0])) > 1e-2;
      }
    }
  EXPECT_TRUE(naiveWouldFail) << "the transform does not tell the inverse transpose from M";
}

// Under a mirroring transform the winding flips, but an outward normal must stay outward: an
// octahedron with outward face normals as vertex normals, and without normals.
TEST(MeshSampling, NormalsStayOutwardUnderAMirror) {
  TriangleMesh oct;
  const glm::vec3 axis[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int sx : {0, 1})
    for (int sy : {2, 3})
      for (int sz : {4, 5}) {
        glm::vec3 a = axis[sx], b = axis[sy], c = axis[sz];
        if (glm::dot(glm::cross(b - a, c - a), a + b + c) < 0) std::swap(b, c);  // outward winding
        const glm::vec3 n = glm::normalize(a + b + c);
        for (const auto& q : {a, b, c}) {
          oct.indices.push_back(uint32_t(oct.positions.size()));
          oct.positions.push_back(q);
          oct.normals.push_back(n);
        }
      }
  TriangleMesh bare = oct;
  bare.normals.clear();
  const glm::mat4 mirror =
      glm::scale(glm::translate(glm::mat4(1), glm::vec3(10, 0, 0)), glm::vec3(-1, 3, 0.5f));
  const glm::vec3 centre(10, 0, 0);
  for (const TriangleMesh* mesh : {&oct, &bare}) {
    SurfelOptions o;
    o.count = 500;
    const Surfels s = sampleSurfels(*mesh, mirror, o);
    for (size_t i = 0; i < s.positions.size(); ++i)
      ASSERT_GT(glm::dot(s.normals[i], s.positions[i] - centre), 0) << "surfel " << i;
  }
}

TEST(MeshSampling, ShadingNormalsInterpolateAndAlbedoIsVertexColourTimesBase) {
  TriangleMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.normals = {glm::normalize(glm::vec3(-1, -1, 2)), glm::normalize(glm::vec3(1, 0, 2)),
               glm::normalize(glm::vec3(0, 1, 2))};
  m.colors = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.indices = {0, 1, 2};
  SurfelOptions o;
  o.count = 200;
  o.baseColor = {0.5f, 0.25f, 1.0f};
  const Surfels s = sampleSurfels(m, glm::mat4(1), o);
  for (size_t i = 0; i < s.positions.size(); ++i) {
    const glm::vec3 p = s.positions[i];
    const float b1 = p.x, b2 = p.y, b0 = 1 - b1 - b2;
    const glm::vec3 n = glm::normalize(b0 * m.normals[0] + b1 * m.normals[1] + b2 * m.normals[2]);
    EXPECT_NEAR(glm::distance(s.normals[i], n), 0, 1e-5);
    const Rgb expect = o.baseColor * (b0 * m.colors[0] + b1 * m.colors[1] + b2 * m.colors[2]);
    EXPECT_NEAR(glm::distance(s.albedo[i], expect), 0, 1e-5);
  }
  m.colors.clear();
  for (const Rgb& a : sampleSurfels(m, glm::mat4(1), o).albedo) EXPECT_EQ(a, o.baseColor);
}

TEST(MeshSampling, DegenerateTrianglesGetNoPoints) {
  TriangleMesh m;
  // A good triangle at z = 1; a collinear one, a repeated-index one and a NaN one at z = 0.
  m.positions = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1},   {0, 0, 0},
                 {1, 0, 0}, {2, 0, 0}, {NAN, 0, 0}, {0, 5, 0}};
  m.indices = {3, 4, 5, 0, 1, 2, 3, 3, 7, 3, 6, 7};
  EXPECT_NEAR(meshArea(m, glm::mat4(1)), 0.5, 1e-7);
  for (auto method : {SurfelSampling::AreaUniform, SurfelSampling::PoissonDisk}) {
    SurfelOptions o;
    o.method = method;
    o.count = 300;
    const Surfels s = sampleSurfels(m, glm::mat4(1), o);
    ASSERT_EQ(s.positions.size(), 300u);
    for (const auto& p : s.positions) ASSERT_EQ(p.z, 1.0f);
  }
  EXPECT_TRUE(sampleSurfels(TriangleMesh{}, glm::mat4(1), {}).positions.empty());
  SurfelOptions none;
  none.count = 0;
  EXPECT_TRUE(sampleSurfels(m, glm::mat4(1), none).positions.empty());
}

TEST(MeshSampling, SameSeedSamePoints) {
  const TriangleMesh square = irregularSquare();
  for (auto method : {SurfelSampling::AreaUniform, SurfelSampling::PoissonDisk}) {
    SurfelOptions o;
    o.method = method;
    o.count = 1500;
    o.seed = 77;
    const Surfels a = sampleSurfels(square, glm::mat4(1), o),
                  b = sampleSurfels(square, glm::mat4(1), o);
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.normals, b.normals);
    o.seed = 78;
    EXPECT_NE(sampleSurfels(square, glm::mat4(1), o).positions, a.positions);
  }
}

}  // namespace
