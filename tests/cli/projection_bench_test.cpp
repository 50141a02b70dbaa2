// `nestlight bench projection`: micro-buffers of the sampled configurations against brute
// force's, at pixels given on the command line.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "test_support.h"

using namespace nestlight;
using json = nlohmann::json;

// A 32 x 24 cornell room of 20k points in dir/room (GL children: no leak checks).
bool makeRoom(const test::TempDir& dir, std::string& out) {
  test::noLeakChecksInGlChildren();
  return test::runCli("make-scene cornell -q -n 20k --width 32 --height 24 -o " + dir.file("room"),
                      &out) == 0;
}

// A small cornell room in the albedo mode: every configuration writes the two receivers'
// micro-buffers, brute force's row is zero against itself, the others' are not (sampled maps
// differ from the reference somewhere), the shares lie in [0, 1], and a pixel outside the image
// is an error naming it.
TEST(ProjectionBench, EveryConfigurationIsComparedWithBruteForce) {
  test::TempDir dir;
  std::string out;
  ASSERT_TRUE(makeRoom(dir, out)) << out;
  ASSERT_EQ(test::runCli("bench projection " + dir.file("room/scene.json") +
                             " --mode albedo --pixel 16,12 --pixel 8,14 -o " + dir.file("b"),
                         &out),
            0)
      << out;
  const json j = json::parse(std::ifstream(dir.file("b/bench_projection.json")));
  for (const char* c : {"brute", "importance", "random", "splat 1", "splat 2", "splat 3"}) {
    ASSERT_TRUE(j["results"].contains(c)) << c << "\n" << out;
    const json& r = j["results"][c];
    EXPECT_EQ(r["pixels"], 2) << c;
    for (const char* k : {"holes", "spill"}) {
      EXPECT_GE(r[k].get<double>(), 0.0) << c << " " << k;
      EXPECT_LE(r[k].get<double>(), 1.0) << c << " " << k;
    }
    if (std::string(c) == "brute")
      EXPECT_EQ(r["rms"].get<double>(), 0.0);
    else
      EXPECT_GT(r["rms"].get<double>(), 0.0) << c;
    std::string folder = c;
    for (char& ch : folder)
      if (ch == ' ') ch = '_';
    EXPECT_TRUE(std::ifstream(dir.file("b/" + folder + "/projection_16_12.exr"))) << c;
  }
  EXPECT_NE(out.find("Targets"), std::string::npos) << out;

  EXPECT_NE(test::runCli("bench projection " + dir.file("room/scene.json") + " --pixel 40,3 -o " +
                             dir.file("b2"),
                         &out),
            0);
  EXPECT_NE(out.find("--pixel: 40,3"), std::string::npos) << out;
}

// --levels (the paper's Fig. 11 and 8): one row per level of the adaptive sampling and one with
// every pixel gathered, each level gathering more pixels than the one before (the last: all), all
// measured against the reference; the indirect light's images written.
TEST(ProjectionBench, LevelsGatherMoreEachAndEveryPixelAll) {
  test::TempDir dir;
  std::string out;
  ASSERT_TRUE(makeRoom(dir, out)) << out;
  ASSERT_EQ(
      test::runCli("bench projection " + dir.file("room/scene.json") +
                       " --levels --mode albedo --runs 1 --reference-spp 8 -o " + dir.file("b"),
                   &out),
      0)
      << out;
  const json j = json::parse(std::ifstream(dir.file("b/bench_projection_levels.json")));
  ASSERT_EQ(j["rows"].size(), 4u) << out;  // grid 4: steps 4, 2, 1; and every pixel
  uint64_t previous = 0;
  for (const json& r : j["rows"]) {
    EXPECT_GT(r["gathered"].get<uint64_t>(), previous) << r["configuration"];
    previous = r["gathered"].get<uint64_t>();
    EXPECT_GT(r["box4"].get<double>(), 0.0);
    EXPECT_LT(r["box4"].get<double>(), 1.0) << r["configuration"];
  }
  EXPECT_EQ(j["rows"][3]["gathered"], j["rows"][3]["receivers"]);
  EXPECT_LT(j["rows"][0]["gathered"].get<uint64_t>(), j["rows"][0]["receivers"].get<uint64_t>());
  EXPECT_TRUE(j["target"].contains("met"));
  for (const char* f : {"indirect_projection.png", "indirect_reference.png",
                        "indirect_difference_2x.png", "levels_every_pixel.png"})
    EXPECT_TRUE(std::ifstream(dir.file("b/" + std::string(f)))) << f;
  EXPECT_NE(test::runCli("bench projection " + dir.file("room/scene.json") +
                             " --levels --pixel 3,3 -o " + dir.file("b2"),
                         &out),
            0);
  EXPECT_NE(out.find("--levels measures whole images"), std::string::npos) << out;
}
