// `nestlight make-scene diffrender`: the ground truth of differential rendering (Rohmer,
// Jendersie, Grosch, "Natural Environment Illumination: Coherent Interactive Augmented Reality
// for Mobile and non-Mobile Devices", 2017) - a captured room with its light, and one inserted
// object.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/mesh.h"
#include "nestlight/gi/scene.h"
#include "nestlight/octree/octree_reader.h"
#include "test_support.h"

using namespace nestlight;
namespace fs = std::filesystem;

namespace {

// make-scene diffrender into dir/name with `extra` options; small, so that a render takes
// a moment. A shared-data folder without the bunny makes the generated object.
gi::Scene makeDiffrender(const test::TempDir& dir, const std::string& name,
                         const std::string& extra) {
  std::string out;
  EXPECT_EQ(test::runCli("make-scene diffrender -q -n 40k --width 16 --height 12 -o " +
                             dir.file(name) + " " + extra,
                         &out),
            0)
      << out;
  return gi::loadScene(dir.path() / name / "scene.json");
}

size_t countMeshes(const gi::Scene& s, bool inserted) {
  size_t n = 0;
  for (const auto& m : s.meshes) n += m.inserted == inserted;
  return n;
}

// The scan is an octree that loads and holds the points asked for.
void expectScanLoads(const gi::Scene& s) {
  ASSERT_EQ(s.octrees.size(), 1u);
  OctreeReader reader(s.octrees[0].path);
  EXPECT_EQ(reader.metadata().points, 40000u);
  EXPECT_GT(reader.readNode(NodeKey{}).size(), 0u);
}

}  // namespace

TEST(DiffrenderScene, PanelIsCapturedTheObjectInserted) {
  test::TempDir dir;
  const gi::Scene s =
      makeDiffrender(dir, "room", "--light panel --shared-data " + dir.file("no-data"));
  EXPECT_EQ(s.gi.method, "diffrender");
  EXPECT_EQ(s.gi.mode, gi::RadianceMode::Albedo);
  ASSERT_EQ(s.meshes.size(), 2u);
  EXPECT_EQ(countMeshes(s, true), 1u);
  EXPECT_EQ(countMeshes(s, false), 1u);
  EXPECT_TRUE(s.lights.empty());
  // The captured panel is what lights the room: its material emits, the object's does not.
  for (const auto& m : s.meshes) {
    const gi::Rgb e = s.materials[m.material].emission;
    EXPECT_EQ(e.r > 0, !m.inserted) << m.path;
    EXPECT_TRUE(fs::exists(m.path)) << m.path;
  }
  EXPECT_TRUE(gi::sceneHasLight(s, gi::RadianceMode::Albedo));
  // Without the shared data the object is generated: the folder is the whole scene.
  EXPECT_FALSE(fs::exists(dir.path() / "room" / "bunny.ply"));
  expectScanLoads(s);

  // Until the diffrender method renders it, the reference (its ground truth) must: lit, finite.
  std::string out;
  const std::string exr = dir.file("ref.exr");
  ASSERT_EQ(test::runCli("render " + dir.file("room/scene.json") +
                             " --method reference --spp 2 --bounces 2 -o " + exr,
                         &out),
            0)
      << out;
  const gi::HdrImage img = gi::readHdrImage(exr);
  EXPECT_EQ(img.width, 16);
  double sum = 0;
  for (float v : img.rgb) {
    ASSERT_TRUE(std::isfinite(v));
    sum += v;
  }
  EXPECT_GT(sum, 0) << "the panel lights nothing the camera sees";
}

// The spot is the default: the reference samples it directly, so the baked capture converges.
TEST(DiffrenderScene, SpotLightReplacesThePanel) {
  test::TempDir dir;
  const gi::Scene s = makeDiffrender(dir, "room", "--shared-data " + dir.file("no-data"));
  ASSERT_EQ(s.lights.size(), 1u);
  EXPECT_EQ(s.lights[0].type, gi::LightType::Spot);
  EXPECT_NEAR(s.lights[0].direction.z, -1.0f, 1e-6f);  // straight down
  // Under the ceiling of the 4 m room.
  EXPECT_GT(s.lights[0].position.z, 3.5);
  EXPECT_LT(s.lights[0].position.z, 4.0);
  ASSERT_EQ(s.meshes.size(), 1u);
  EXPECT_TRUE(s.meshes[0].inserted);
  expectScanLoads(s);
}

TEST(DiffrenderScene, LightIsAnErrorForOtherKinds) {
  test::TempDir dir;
  std::string out;
  EXPECT_EQ(test::runCli("make-scene cornell -q -n 10k --light spot -o " + dir.file("c"), &out), 1)
      << out;
  EXPECT_NE(out.find("--light"), std::string::npos) << out;
  EXPECT_NE(out.find("diffrender"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir.path() / "c" / "scene.json"));
}

TEST(DiffrenderScene, TheStanfordBunnyStandsOnTheFloor) {
  NL_REQUIRE_SHARED("meshes/bunny.ply");
  test::TempDir dir;
  const gi::Scene s = makeDiffrender(dir, "room", "--shared-data " + test::sharedData().string());
  ASSERT_EQ(countMeshes(s, true), 1u);
  const gi::SceneMesh& bunny = s.meshes[0];
  ASSERT_TRUE(bunny.inserted);
  // Copied into the folder, so the scene outlives the shared data.
  EXPECT_EQ(bunny.path, (dir.path() / "room" / "bunny.ply").lexically_normal());
  const gi::TriangleMesh mesh = gi::readMesh(bunny.path.string());
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  for (const glm::vec3& p : mesh.positions) {
    const glm::dvec3 w = glm::dvec3(bunny.worldFromObject * glm::dvec4(glm::dvec3(p), 1.0));
    lo = glm::min(lo, w);
    hi = glm::max(hi, w);
  }
  // Its feet on the floor (z = 0) within 5 mm, the placement's rounding; upright and about
  // 0.6 m tall; inside the 4 m room.
  EXPECT_NEAR(lo.z, 0.0, 0.005);
  EXPECT_NEAR(hi.z - lo.z, 0.62, 0.02);
  EXPECT_GT(lo.x, 0.0);
  EXPECT_GT(lo.y, 0.0);
  EXPECT_LT(hi.x, 4.0);
  EXPECT_LT(hi.y, 4.0);
}
