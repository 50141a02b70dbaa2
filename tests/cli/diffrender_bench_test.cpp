// `nestlight bench gi` on differential rendering's ground truth (`make-scene diffrender`): R0, the
// reference without the inserted meshes, and the rows' dL, object and material errors.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "nestlight/gi/scene.h"
#include "nestlight/octree/octree_reader.h"
#include "test_support.h"

using namespace nestlight;
using json = nlohmann::json;

namespace {

bool finiteNumber(const json& v) {
  return v.is_number() && std::isfinite(v.get<double>());
}

const json* findRow(const json& rows, const std::string& method, const std::string& variant) {
  for (const json& r : rows)
    if (r["method"] == method && r["variant"] == variant) return &r;
  return nullptr;
}

}  // namespace

TEST(DiffrenderBench, RowsCarryTheDifferentialErrors) {
  test::TempDir dir;
  std::string out;
  test::noLeakChecksInGlChildren();
  // The generated sphere (no shared data) under the spot, 4k points: a second's bake.
  ASSERT_EQ(test::runCli("make-scene diffrender -q -n 4k --width 32 --height 24 --bake-spp 4 "
                         "--shared-data " +
                             dir.file("no-data") + " -o " + dir.file("room"),
                         &out),
            0)
      << out;
  EXPECT_NE(out.find("mean relative standard error"), std::string::npos) << out;
  // make-scene baked the capture its scene names, so diffrender renders the scene as written.
  const gi::Scene s = gi::loadScene(dir.path() / "room" / "scene.json");
  ASSERT_EQ(s.gi.parameters.value("capture", ""), "captured");
  const OctreeReader reader(s.octrees[0].path);  // the record lives in the reader's metadata
  const LayerRecord* layer = reader.metadata().layer("captured");
  ASSERT_NE(layer, nullptr);
  EXPECT_EQ(layer->kind, "colour");

  ASSERT_EQ(test::runCli("bench gi " + dir.file("room/scene.json") +
                             " --methods diffrender,vpl --no-variants --runs 1 "
                             "--quality diffrender=8 --quality vpl=16 --reference-error 0.05 "
                             "--reference-spp 256 -o " +
                             dir.file("b"),
                         &out),
            0)
      << out;
  EXPECT_NE(out.find("R0 (the reference without the inserted meshes"), std::string::npos) << out;
  std::ifstream csv(dir.file("b/bench_gi.csv"));
  std::string header;
  std::getline(csv, header);
  EXPECT_NE(header.find(",delta_l2_scan,object_l2,rho_l2,skipped"), std::string::npos) << header;

  const json j = json::parse(test::readFile(dir.file("b/bench_gi.json")));
  const json& d = j["differential"];
  ASSERT_TRUE(d.is_object()) << j.dump();
  EXPECT_TRUE(finiteNumber(d["r0_relative_l2"])) << d.dump();
  EXPECT_EQ(d["delta_scale"], 2);  // diffrender's default, read from its dL image's size
  EXPECT_GT(d["scan_blocks"].get<int>(), 0);
  ASSERT_GT(d["object_pixels"].get<int>(), 0);
  // R0 has no sphere where R1 has one: its object pixels show the floor behind, far off.
  EXPECT_GT(d["r0_object_l2"].get<double>(), 0.3) << d.dump();
  // The capture is R0's scan pixels up to the bake's noise (4 paths a point: about 0.5 a point):
  // a black capture would be 1 off, and albedos shown as radiance (about 0.5 against a lit
  // radiance near 0.1) several times that.
  EXPECT_LT(d["capture_l2_scan"].get<double>(), 1.0) << d.dump();
  // R0's dL is 0: its error against R1 - R0 is 1 by definition.
  EXPECT_DOUBLE_EQ(d["r0_delta_l2"].get<double>(), 1.0);

  const json* dr = findRow(j["rows"], "diffrender", "");
  ASSERT_NE(dr, nullptr) << j["rows"].dump();
  for (const char* key : {"delta_l2", "object_l2", "rho_l2"})
    EXPECT_TRUE(finiteNumber((*dr)[key])) << key << ": " << dr->dump();
  // diffrender draws the sphere, lit from the capture: closer to R1 there than R0's floor.
  EXPECT_LT((*dr)["object_l2"].get<double>(), d["r0_object_l2"].get<double>()) << dr->dump();
  // The material estimate is an albedo: within a factor of two of the scan's on average even at
  // 8 samples over a 4-path capture (rho_l2 < 1 rules out a missing or unscaled rho image).
  EXPECT_LT((*dr)["rho_l2"].get<double>(), 1.0) << dr->dump();

  // vpl as the scene sets it has no differential columns; its two-simulation baseline has dL and
  // object errors but no material estimate.
  const json* vpl = findRow(j["rows"], "vpl", "");
  ASSERT_NE(vpl, nullptr);
  EXPECT_TRUE((*vpl)["delta_l2"].is_null()) << vpl->dump();
  const json* two = findRow(j["rows"], "vpl", "two-simulation");
  ASSERT_NE(two, nullptr) << j["rows"].dump();
  EXPECT_TRUE(finiteNumber((*two)["delta_l2"])) << two->dump();
  EXPECT_TRUE(finiteNumber((*two)["object_l2"])) << two->dump();
  EXPECT_TRUE((*two)["rho_l2"].is_null()) << two->dump();
  EXPECT_TRUE(finiteNumber((*two)["relative_l2"])) << two->dump();
}
