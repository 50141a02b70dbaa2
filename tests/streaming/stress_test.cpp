// The stress test of `nestlight stress`, smaller: 2000 frames of teleports, fast flights, orbits
// and stops over a 1M-point octree with tiny budgets that change at run time.
#include "nestlight/streaming/stress.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "nestlight/octree/octree_reader.h"
#include "streaming_support.h"
#include "test_support.h"

using namespace nestlight;
using namespace nestlight::streaming;

TEST(Stress, TwoThousandFramesTinyBudgets) {
  test::TempDir t;
  SyntheticSpec spec;
  spec.points = 1'000'000;
  spec.seed = 4;
  test::buildSyntheticOctree(t.path() / "o", spec, 4000);
  OctreeReader reader(t.path() / "o");
  StressOptions o;
  o.frames = 2000;
  o.seed = 12;
  o.budgets.points = 150'000;
  o.budgets.gpuBytes = 2u << 20;
  o.budgets.uploadBytesPerFrame = 256u << 10;
  o.budgets.loaderThreads = 2;
  o.frameMs = 2;
  o.settleFrames = 2000;
  const StressReport r = runStress(reader, o);
  for (const auto& v : r.violations) ADD_FAILURE() << v;
  EXPECT_TRUE(r.ok());
  EXPECT_GE(r.frames, 2000u);
  EXPECT_GT(r.stops, 1u);
  EXPECT_EQ(r.renderThreadReaderCalls, 0u);
  EXPECT_LE(r.maxResidentBytes, 2u * (2u << 20));  // the largest budget the run scaled to
  EXPECT_GT(r.totals.evicted, 0u);
  EXPECT_GT(r.totals.cancelled, 0u);
  EXPECT_EQ(r.totals.requested, r.totals.completed + r.totals.cancelled + r.totals.failed);
  std::printf(
      "stress: %llu frames, %llu stops (settle median %llu, max %llu frames), update ms median "
      "%.3f p99 %.3f max %.3f, %llu loads, %llu cancelled, %llu evictions\n",
      (unsigned long long)r.frames, (unsigned long long)r.stops,
      (unsigned long long)r.settleFramesMedian, (unsigned long long)r.settleFramesMax,
      r.updateMsMedian, r.updateMsP99, r.updateMsMax, (unsigned long long)r.totals.completed,
      (unsigned long long)r.totals.cancelled, (unsigned long long)r.totals.evicted);
}

TEST(Stress, CommandLineSummaryAndJson) {
  test::TempDir t;
  std::string out;
  ASSERT_EQ(test::runCli("stress --generate 150k --dir " + t.file("o") +
                             " --frames 300 --frame-ms 1 --point-budget 40k --gpu-budget 1M "
                             "--upload-budget 128k -q --json " +
                             t.file("s.json"),
                         &out),
            0)
      << out;
  EXPECT_NE(out.find("result     OK"), std::string::npos) << out;
  EXPECT_NE(out.find("calls on the render thread inside update(): 0"), std::string::npos) << out;
  const nlohmann::json j = nlohmann::json::parse(test::readFile(t.file("s.json")));
  EXPECT_TRUE(j["ok"].get<bool>());
  EXPECT_GE(j["frames"].get<uint64_t>(), 300u);
  EXPECT_EQ(j["render_thread_reader_calls"], 0);
  EXPECT_EQ(j["points"], 150000);

  // A folder that is not an octree: a clear message and a non-zero exit.
  EXPECT_NE(test::runCli("stress " + t.file("nothing"), &out), 0);
  EXPECT_NE(out.find("metadata.json"), std::string::npos) << out;
}
