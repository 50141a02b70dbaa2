// `nestlight bench clip` runs its three operations on a generated octree and reports what each
// read and kept; the figures agree with a direct count.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "nestlight/converters/export.h"
#include "nestlight/octree/clip_volume.h"
#include "test_support.h"

using nestlight::test::TempDir;

TEST(BenchClip, ReportsEachOperationWithCountsThatAgreeWithACount) {
  TempDir tmp;
  std::string out;
  ASSERT_EQ(nestlight::test::runCli("bench clip --points 100k --runs 1 --dir " +
                                        tmp.path().string() + " --json " + tmp.file("r.json"),
                                    &out),
            0)
      << out;
  std::ifstream f(tmp.file("r.json"));
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_EQ(j["points"], 100000);
  ASSERT_EQ(j["results"].size(), 3u);
  const nestlight::ClipSet box = nestlight::ClipSet::load(tmp.path() / "bench_clip_box.json");
  nestlight::ExportOptions o;
  o.clip = &box;
  const uint64_t kept = nestlight::countOctree(tmp.path() / "clip_100k.octree", o).points;
  EXPECT_GT(kept, 1000u);
  EXPECT_LT(kept, 50000u);
  for (const auto& r : j["results"]) {
    EXPECT_GT(r["median_seconds"].get<double>(), 0) << r.dump();
    EXPECT_GT(r["peak_rss_bytes"].get<double>(), 0) << r.dump();
    EXPECT_GE(r["points_read"].get<uint64_t>(), r["points_kept"].get<uint64_t>()) << r.dump();
  }
  EXPECT_EQ(j["results"][0]["points_kept"], kept);  // export --clip
  EXPECT_EQ(j["results"][1]["points_kept"], kept);  // info --clip
}
