// The `bench stream` harness as a library call: every measure reported, and a converged view never
// reads less than the payload of the nodes it draws.
#include "nestlight/bench/stream_bench.h"

#include <gtest/gtest.h>

#include "streaming/streaming_support.h"
#include "test_support.h"

using namespace nestlight;

TEST(StreamBench, ReportsEveryMeasure) {
  test::TempDir t;
  SyntheticSpec spec;
  spec.points = 100'000;
  spec.seed = 5;
  test::buildSyntheticOctree(t.path() / "o", spec, 2000);
  bench::StreamBenchOptions o;
  o.frames = 20;
  o.teleports = 2;
  o.frameMs = 1;
  o.device = "test";
  const nlohmann::json r = bench::runStreamBench(t.path() / "o", o, nullptr);
  EXPECT_EQ(r["device"], "test");
  EXPECT_EQ(r["points"], 100'000u);
  ASSERT_EQ(r["paths"].size(), 3u);
  for (const auto& p : r["paths"]) EXPECT_GT(p["cut_nodes_mean"].get<double>(), 0) << p.dump();
  EXPECT_EQ(r["teleports"].size(), 2u);
  // Every byte a converged view draws was read at least once (a ratio below 1 would mean the
  // accounting lost reads).
  EXPECT_GE(r["bytes_read_ratio"]["median"].get<double>(), 1.0);
  EXPECT_GE(r["teleport"]["frames_median"].get<double>(), 1.0);
}
