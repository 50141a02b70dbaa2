// The object volume's solid voxelisation (nestlight/gi/diffrender/object_volume.h): the enclosed
// volume by parity, exact counts where every voxel centre is decided without rounding (dyadic
// grids, columns through shared edges and vertices), open meshes, the shell's normals and
// materials, and bad input.
#include "nestlight/gi/diffrender/object_volume.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>

#include "nestlight/converters/test_scenes.h"
#include "nestlight/gi/mesh.h"
#include "test_support.h"

namespace nestlight::gi {
// Named: the folder's test files share translation units (unity builds).
namespace object_volume_test {
namespace {

using test::TempDir;

TriangleMesh icosphere(int subdivisions) {
  TempDir dir;
  writeIcosphereObj(dir.path() / "sphere.obj", subdivisions);
  return readMesh(dir.file("sphere.obj"));
}

// The unit box [0, 1]^3, counter-clockwise seen from outside; its top face (z = 1) is triangles 2
// and 3, its top and bottom faces are split along the diagonal x = y.
TriangleMesh unitBox() {
  TempDir dir;
  writeBoxObj(dir.path() / "box.obj");
  return readMesh(dir.file("box.obj"));
}

// The octahedron |x| + |y| + |z| = r, counter-clockwise seen from outside.
TriangleMesh octahedron(float r) {
  TriangleMesh m;
  m.positions = {{r, 0, 0}, {-r, 0, 0}, {0, r, 0}, {0, -r, 0}, {0, 0, r}, {0, 0, -r}};
  for (uint32_t x : {0u, 1u})
    for (uint32_t y : {2u, 3u})
      for (uint32_t z : {4u, 5u}) {
        // (x, y, z) is counter-clockwise when the octant's sign product is positive.
        const bool ccw = ((x == 0) == (y == 2)) == (z == 4);
        m.indices.insert(m.indices.end(), {x, ccw ? y : z, ccw ? z : y});
      }
  return m;
}

// The enclosed volume by the divergence theorem: the facets' own volume, not the sphere's.
double enclosedVolume(const TriangleMesh& m, const glm::mat4& xf) {
  double v = 0;
  for (size_t t = 0; t < m.triangles(); ++t) {
    glm::dvec3 p[3];
    for (int c = 0; c < 3; ++c)
      p[c] =
          glm::dvec3(glm::dmat4(xf) * glm::dvec4(glm::dvec3(m.positions[m.indices[3 * t + c]]), 1));
    v += glm::dot(p[0], glm::cross(p[1], p[2])) / 6;
  }
  return v;
}

size_t index(const ObjectVolume& v, int x, int y, int z) {
  return size_t(x) + size_t(v.size.x) * (size_t(y) + size_t(v.size.y) * size_t(z));
}

glm::dvec3 centre(const ObjectVolume& v, int x, int y, int z) {
  return glm::dvec3(v.lo) + (glm::dvec3(x, y, z) + 0.5) * glm::dvec3(v.voxelSize());
}

glm::dvec3 decodeNormal(uint32_t s) {
  return glm::dvec3(double(s & 255), double((s >> 8) & 255), double((s >> 16) & 255)) / 127.5 - 1.0;
}

TEST(ObjectVolume, SphereParityVolumeIsTheMeshVolume) {
  // The volume counted is that of the voxels whose centre is inside by parity (parityVoxels),
  // without the surface shell, which would add a layer as thick as the surface's voxels. At 64^3
  // the sphere's radius is 31 voxels; counting lattice points in a convex body errs by about its
  // surface in voxels times a fraction that averages out over the sphere (the lattice point
  // problem: O(r^1.5) of O(r^3), here well under 1%). A fill rule off by one voxel per column
  // would add or remove pi r^2 / (4/3 pi r^3) = 2.4%: the 1% bound tells the two apart.
  const TriangleMesh sphere = icosphere(4);
  const glm::mat4 xf =
      glm::scale(glm::translate(glm::mat4(1), glm::vec3(3.1f, -1.7f, 0.4f)), glm::vec3(2.5f));
  const ObjectVolume v = voxelizeSolid({{&sphere, xf, 0, "sphere"}}, glm::ivec3(64));
  EXPECT_TRUE(v.warnings.empty()) << v.warnings[0];
  EXPECT_EQ(v.skippedTriangles, 0u);
  const glm::dvec3 d(v.voxelSize());
  EXPECT_NEAR(d.x, 5.0 / 62, 0.01 * 5.0 / 62);  // the icosphere reaches almost to radius 1
  const double expected = enclosedVolume(sphere, xf);
  const double measured = double(v.parityVoxels) * d.x * d.y * d.z;
  EXPECT_NEAR(measured / expected, 1.0, 0.01) << measured << " vs " << expected;
  // The shell adds to the parity interior, and lies within it or around it.
  EXPECT_GT(v.solidVoxels, v.parityVoxels);
  EXPECT_LE(v.solidVoxels, v.parityVoxels + v.boundaryVoxels);
  EXPECT_EQ(v.bytes(), size_t(64 * 64 * 64) * 5);
  // Rays see the interior and not the shell's excess outside it: the voxels marked fully solid
  // hold the sphere's volume within 1% too (every shell voxel here borders the interior).
  const auto full = std::count(v.occupancy.begin(), v.occupancy.end(), uint8_t(255));
  EXPECT_NEAR(double(full) * d.x * d.y * d.z / expected, 1.0, 0.01);
  EXPECT_GT(std::count(v.occupancy.begin(), v.occupancy.end(), ObjectVolume::kShell), 0);
  // The padding stays empty: the sphere touches its bounds only at single points.
  for (int z = 0; z < 64; ++z)
    for (int y = 0; y < 64; ++y) {
      EXPECT_EQ(v.occupancy[index(v, 0, y, z)], 0);
      EXPECT_EQ(v.occupancy[index(v, 63, y, z)], 0);
    }
}

TEST(ObjectVolume, BoxWithFacesBetweenVoxelCentresIsExact) {
  // Faces on voxel boundaries: the interior is every voxel but the padding, and the shell is its
  // outer layer, not the padding beside it. The top and bottom faces' shared diagonal x = y runs
  // through the centres of the columns x == y (with 10 voxels the grid is dyadic: exact).
  const TriangleMesh box = unitBox();
  for (const glm::ivec3 n : {glm::ivec3(10), glm::ivec3(10, 13, 7)}) {
    SCOPED_TRACE(testing::Message() << n.x << "x" << n.y << "x" << n.z);
    const ObjectVolume v = voxelizeSolid({{&box, glm::mat4(1), 2, "box"}}, n);
    EXPECT_TRUE(v.warnings.empty());
    const glm::ivec3 in = n - 2, core = n - 4;
    EXPECT_EQ(v.parityVoxels, uint64_t(in.x) * uint64_t(in.y) * uint64_t(in.z));
    EXPECT_EQ(v.solidVoxels, v.parityVoxels);
    EXPECT_EQ(v.boundaryVoxels,
              v.parityVoxels - uint64_t(core.x) * uint64_t(core.y) * uint64_t(core.z));
    for (int a = 0; a < 3; ++a) {
      EXPECT_FLOAT_EQ(v.lo[a], -1.0f / float(in[a]));
      EXPECT_FLOAT_EQ(v.hi[a], 1.0f + 1.0f / float(in[a]));
    }
    for (int z = 0; z < n.z; ++z)
      for (int y = 0; y < n.y; ++y)
        for (int x = 0; x < n.x; ++x) {
          const bool inside =
              x >= 1 && x <= n.x - 2 && y >= 1 && y <= n.y - 2 && z >= 1 && z <= n.z - 2;
          ASSERT_EQ(v.occupancy[index(v, x, y, z)], inside ? 255 : 0) << x << " " << y << " " << z;
        }
    // A voxel in the middle of the face x = 1: normal +x, material 2.
    const uint32_t s = v.surface[index(v, n.x - 2, n.y / 2, n.z / 2)];
    EXPECT_EQ(s >> 24, 3u);
    EXPECT_GT(glm::dot(decodeNormal(s), glm::dvec3(1, 0, 0)), 0.99);
    EXPECT_EQ(v.surface[index(v, n.x / 2, n.y / 2, n.z / 2)], 0u);
  }
}

TEST(ObjectVolume, ColumnsThroughSharedEdgesAndVerticesCrossOnce) {
  // r = 1.125 over 11 voxels: voxel size 0.25, centres at multiples of 0.25, so the column x = y
  // = 0 passes through both apexes (four triangles meet at each), the columns x = 0 or y = 0
  // through edges, and no centre lies on a face (|x| + |y| + |z| is a multiple of 0.25). Each
  // must cross the surface exactly twice: no warning, and exactly the centres inside are filled.
  // The mirrored octahedron is wound the other way seen from +z.
  const TriangleMesh oct = octahedron(1.125f);
  for (const glm::mat4& xf : {glm::mat4(1), glm::scale(glm::mat4(1), glm::vec3(1, -1, 1))}) {
    const ObjectVolume v = voxelizeSolid({{&oct, xf, 0, "octahedron"}}, glm::ivec3(11));
    EXPECT_TRUE(v.warnings.empty()) << v.warnings[0];
    ASSERT_EQ(v.voxelSize(), glm::vec3(0.25f));
    uint64_t expected = 0;
    for (int z = 0; z < 11; ++z)
      for (int y = 0; y < 11; ++y)
        for (int x = 0; x < 11; ++x) {
          const glm::dvec3 c = centre(v, x, y, z);
          if (std::abs(c.x) + std::abs(c.y) + std::abs(c.z) >= 1.125) continue;
          ++expected;
          EXPECT_EQ(v.occupancy[index(v, x, y, z)], 255) << x << " " << y << " " << z;
        }
    EXPECT_EQ(expected, 129u);  // integer points of L1 norm up to 4: 1 + 6 + 18 + 38 + 66
    EXPECT_EQ(v.parityVoxels, expected);
    // The apex column: the nine centres with |z| < 1.125.
    for (int z = 1; z <= 9; ++z) EXPECT_EQ(v.occupancy[index(v, 5, 5, z)], 255) << z;
  }
}

TEST(ObjectVolume, OpenBoxWarnsAndKeepsOnlyItsShell) {
  TriangleMesh box = unitBox();
  box.indices.erase(box.indices.begin() + 6, box.indices.begin() + 12);  // the top face
  const ObjectVolume v =
      voxelizeSolid({{&box, glm::mat4(1), 0, "meshes[0].path (open.obj)"}}, glm::ivec3(10));
  ASSERT_EQ(v.warnings.size(), 1u);
  EXPECT_NE(v.warnings[0].find("meshes[0].path (open.obj)"), std::string::npos) << v.warnings[0];
  // Every column over the box meets the bottom face alone.
  EXPECT_NE(v.warnings[0].find("64 of 100"), std::string::npos) << v.warnings[0];
  EXPECT_EQ(v.parityVoxels, 0u);
  // The bottom layer and the four side layers of the 8^3 inside, the top layer's middle open.
  EXPECT_EQ(v.solidVoxels, 8u * 8 * 8 - 6u * 6 * 7);
  EXPECT_EQ(v.boundaryVoxels, v.solidVoxels);
  EXPECT_EQ(v.occupancy[index(v, 5, 5, 5)], 0);
  EXPECT_EQ(v.occupancy[index(v, 5, 5, 1)], 255);
}

TEST(ObjectVolume, SphereShellNormalsPointOutwardAndCarryTheMaterial) {
  // Area-weighted facet normals of a sphere differ from the radial direction at a voxel centre by
  // the angle the voxel subtends (r = 31 voxels: a few degrees) and, at voxels the surface only
  // grazes, by more: dot > 0.8 (37 degrees) for 95% leaves room for the grazed ones. The mirrored
  // sphere's windings are clockwise: its outward normals must still point out.
  const TriangleMesh sphere = icosphere(4);
  for (const glm::mat4& xf : {glm::mat4(1), glm::scale(glm::mat4(1), glm::vec3(-1, 1, 1))}) {
    const ObjectVolume v = voxelizeSolid({{&sphere, xf, 5, "sphere"}}, glm::ivec3(64));
    ASSERT_GT(v.boundaryVoxels, 1000u);
    uint64_t outward = 0, seen = 0;
    const double d = v.voxelSize().x;
    for (int z = 0; z < 64; ++z)
      for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
          const uint32_t s = v.surface[index(v, x, y, z)];
          if (s == 0) continue;
          ++seen;
          EXPECT_EQ(s >> 24, 6u);
          EXPECT_NE(v.occupancy[index(v, x, y, z)], 0);
          const glm::dvec3 c = centre(v, x, y, z);
          EXPECT_NEAR(glm::length(c), 1.0, std::sqrt(3.0) * d);  // the shell is on the surface
          if (glm::dot(decodeNormal(s), glm::normalize(c)) > 0.8) ++outward;
        }
    EXPECT_EQ(seen, v.boundaryVoxels);
    EXPECT_GE(double(outward), 0.95 * double(seen));
  }
}

TEST(ObjectVolume, MeshesKeepTheirMaterialsAndTheirOwnInteriors) {
  const TriangleMesh box = unitBox();
  // Apart: each shell voxel carries its own box's material.
  {
    const glm::mat4 right = glm::translate(glm::mat4(1), glm::vec3(2, 0, 0));
    const ObjectVolume v = voxelizeSolid(
        {{&box, glm::mat4(1), 3, "left"}, {&box, right, 7, "right"}}, glm::ivec3(26, 10, 10));
    uint64_t left = 0, rightCount = 0;
    for (int z = 0; z < 10; ++z)
      for (int y = 0; y < 10; ++y)
        for (int x = 0; x < 26; ++x) {
          const uint32_t s = v.surface[index(v, x, y, z)];
          if (s == 0) continue;
          const bool isLeft = centre(v, x, y, z).x < 1.5;
          EXPECT_EQ(s >> 24, isLeft ? 4u : 8u) << x << " " << y << " " << z;
          ++(isLeft ? left : rightCount);
        }
    EXPECT_GT(left, 0u);
    EXPECT_EQ(left, rightCount);
  }
  // Overlapping: filled one by one, the overlap stays solid (the parity of both together would
  // empty it) and neither box is open.
  {
    const glm::mat4 shifted = glm::translate(glm::mat4(1), glm::vec3(0.5f, 0.25f, 0.125f));
    const ObjectVolume v =
        voxelizeSolid({{&box, glm::mat4(1), 1, "a"}, {&box, shifted, 2, "b"}}, glm::ivec3(40));
    EXPECT_TRUE(v.warnings.empty());
    uint64_t expected = 0;
    for (int z = 0; z < 40; ++z)
      for (int y = 0; y < 40; ++y)
        for (int x = 0; x < 40; ++x) {
          const glm::dvec3 c = centre(v, x, y, z);
          const auto in = [&](glm::dvec3 o) {
            return glm::all(glm::greaterThan(c, o)) && glm::all(glm::lessThan(c, o + 1.0));
          };
          if (!in(glm::dvec3(0)) && !in(glm::dvec3(0.5, 0.25, 0.125))) continue;
          ++expected;
          EXPECT_EQ(v.occupancy[index(v, x, y, z)], 255) << x << " " << y << " " << z;
        }
    EXPECT_EQ(v.parityVoxels, expected);
  }
}

TEST(ObjectVolume, BadTrianglesAreSkippedWithoutChangingTheResult) {
  const TriangleMesh clean = unitBox();
  TriangleMesh bad = clean;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const uint32_t base = uint32_t(bad.positions.size());
  // A NaN corner, an infinite corner, collinear corners far outside the box (they would widen
  // the bounds), a repeated index, an index past the end.
  bad.positions.insert(bad.positions.end(),
                       {{nan, 0.5f, 0.5f}, {0.5f, inf, 0.5f}, {5, 5, 5}, {6, 6, 6}, {7, 7, 7}});
  const std::vector<uint32_t> extra = {0,        1, base, 2, base + 1, 3, base + 2, base + 3,
                                       base + 4, 4, 4,    5, 0,        1, base + 9};
  bad.indices.insert(bad.indices.begin() + 6, extra.begin(), extra.end());
  const ObjectVolume a = voxelizeSolid({{&clean, glm::mat4(1), 1, "box"}}, glm::ivec3(12));
  const ObjectVolume b = voxelizeSolid({{&bad, glm::mat4(1), 1, "box"}}, glm::ivec3(12));
  EXPECT_EQ(b.skippedTriangles, 5u);
  EXPECT_EQ(a.lo, b.lo);
  EXPECT_EQ(a.hi, b.hi);
  EXPECT_EQ(a.occupancy, b.occupancy);
  EXPECT_EQ(a.surface, b.surface);
  EXPECT_EQ(a.solidVoxels, b.solidVoxels);
  EXPECT_TRUE(b.warnings.empty());
  // A non-finite transform leaves nothing to voxelise.
  const glm::mat4 nanXf(nan);
  const ObjectVolume c = voxelizeSolid({{&clean, nanXf, 1, "box"}}, glm::ivec3(4));
  EXPECT_EQ(c.skippedTriangles, 12u);
  EXPECT_EQ(c.solidVoxels, 0u);
}

TEST(ObjectVolume, EmptyAndFlatInputGiveUsableGrids) {
  const ObjectVolume none = voxelizeSolid({}, glm::ivec3(4, 5, 6));
  EXPECT_EQ(none.size, glm::ivec3(4, 5, 6));
  EXPECT_EQ(none.occupancy.size(), 120u);
  EXPECT_EQ(none.solidVoxels, 0u);
  EXPECT_TRUE(glm::all(glm::lessThan(none.lo, none.hi)));
  const TriangleMesh empty;
  EXPECT_EQ(voxelizeSolid({{&empty, glm::mat4(1), 0, "empty"}}, glm::ivec3(3)).solidVoxels, 0u);

  // A square at z = 0 (flat along z): the z axis gets the x and y voxel size, the square one
  // layer of voxels, and every column over it one crossing (open).
  TriangleMesh square;
  square.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  square.indices = {0, 1, 2, 0, 2, 3};
  const ObjectVolume v = voxelizeSolid({{&square, glm::mat4(1), 0, "square"}}, glm::ivec3(8));
  EXPECT_FLOAT_EQ(v.voxelSize().z, v.voxelSize().x);
  EXPECT_LT(v.lo.z, 0.0f);
  EXPECT_GT(v.hi.z, 0.0f);
  ASSERT_EQ(v.warnings.size(), 1u);
  EXPECT_NE(v.warnings[0].find("36 of 64"), std::string::npos) << v.warnings[0];
  EXPECT_EQ(v.boundaryVoxels, 36u);
  EXPECT_EQ(v.solidVoxels, 36u);
}

TEST(ObjectVolume, BadSizesAndMaterialsThrow) {
  const TriangleMesh box = unitBox();
  const std::vector<VolumeMesh> one = {{&box, glm::mat4(1), 0, "box"}};
  EXPECT_NE(test::errorOf([&] { voxelizeSolid(one, glm::ivec3(0, 4, 4)); }).reason().find("size"),
            std::string::npos);
  test::errorOf([&] { voxelizeSolid(one, glm::ivec3(4, -1, 4)); });
  EXPECT_NE(test::errorOf([&] { voxelizeSolid(one, glm::ivec3(2048)); }).reason().find("2^31"),
            std::string::npos);
  EXPECT_NE(test::errorOf([&] {
              voxelizeSolid({{&box, glm::mat4(1), 255, "box"}}, glm::ivec3(4));
            })
                .reason()
                .find("box"),
            std::string::npos);
  test::errorOf([&] { voxelizeSolid({{nullptr, glm::mat4(1), 0, "none"}}, glm::ivec3(4)); });
  // Small sizes have no padding but still hold the mesh: along x one voxel is the box, along y
  // two voxels of its size are centred on it, along z three (padded). The box is then the voxels
  // (0, 0..1, 1).
  const ObjectVolume v = voxelizeSolid(one, glm::ivec3(1, 2, 3));
  EXPECT_EQ(v.lo, glm::vec3(0, -0.5f, -1));
  EXPECT_EQ(v.hi, glm::vec3(1, 1.5f, 2));
  EXPECT_EQ(v.solidVoxels, 2u);
  for (size_t i = 0; i < v.occupancy.size(); ++i)
    EXPECT_EQ(v.occupancy[i] != 0, i == 2 || i == 3) << i;
}

TEST(ObjectVolume, BunnyIsFilled) {
  NL_REQUIRE_SHARED("meshes/bunny.ply");
  const TriangleMesh bunny = readMesh((test::sharedData() / "meshes" / "bunny.ply").string());
  const auto t0 = std::chrono::steady_clock::now();
  const ObjectVolume v =
      voxelizeSolid({{&bunny, glm::mat4(1), 0, "bunny.ply"}}, glm::ivec3(128, 96, 96));
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  RecordProperty("seconds", std::to_string(s));
  std::printf("bunny: %zu triangles, %.3f s, %llu solid, %llu shell, %zu warnings%s%s\n",
              bunny.triangles(), s, (unsigned long long)v.solidVoxels,
              (unsigned long long)v.boundaryVoxels, v.warnings.size(),
              v.warnings.empty() ? "" : ": ", v.warnings.empty() ? "" : v.warnings[0].c_str());
  EXPECT_GT(v.parityVoxels, v.boundaryVoxels);  // a filled body, not a shell
}

}  // namespace
}  // namespace object_volume_test
}  // namespace nestlight::gi
