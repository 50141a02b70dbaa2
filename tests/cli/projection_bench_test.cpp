// `nestlight bench projection`: micro-buffers of the sampled configurations against brute
// force's, at pixels given on the command line.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "test_support.h"

using namespace nestlight;
using json = nlohmann::json;

// A small cornell room in the albedo mode: every configuration writes the two receivers'
// micro-buffers, brute force's row is zero against itself, the others' are not (sampled maps
// differ from the reference somewhere), the shares lie in [0, 1], and a pixel outside the image
// is an error naming it.
TEST(ProjectionBench, EveryConfigurationIsComparedWithBruteForce) {
  test::TempDir dir;
  std::string out;
  test::noLeakChecksInGlChildren();
  ASSERT_EQ(test::runCli(
                "make-scene cornell -q -n 20k --width 32 --height 24 -o " + dir.file("room"), &out),
            0)
      << out;
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
