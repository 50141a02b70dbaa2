// `nestlight bench diffrender` at a toy size: every table has its rows, the errors are finite and
// not negative, the equal-time pick keeps to its budget, and bad options are errors naming them.
#include "nestlight/bench/bench_diffrender.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "test_support.h"

namespace {

using json = nlohmann::json;
using nestlight::bench::equalTimePick;

TEST(BenchDiffrenderEqualTime, PicksTheLargestNWithinTheBudget) {
  const std::vector<std::pair<int, double>> sweep = {{8, 50}, {16, 80}, {32, 120}, {64, 90}};
  // 64 samples at 90 ms (a noisy time below 32's) is within 100 ms: the largest N that fits.
  ASSERT_TRUE(equalTimePick(sweep, 100));
  EXPECT_EQ(*equalTimePick(sweep, 100), 3u);
  EXPECT_EQ(*equalTimePick(sweep, 85), 1u);
  EXPECT_EQ(*equalTimePick(sweep, 80), 1u) << "a time equal to the budget fits";
  EXPECT_FALSE(equalTimePick(sweep, 49.9)) << "nothing fits";
  EXPECT_FALSE(equalTimePick({}, 100));
}

bool finiteNonNegative(const json& v) {
  return v.is_number() && std::isfinite(v.get<double>()) && v.get<double>() >= 0;
}

const json& rowsOf(const json& j, const std::string& table) {
  return j.at("tables").at(table).at("rows");
}

TEST(BenchDiffrender, WritesItsTablesAndKeepsToTheBudget) {
  nestlight::test::TempDir dir;
  nestlight::test::noLeakChecksInGlChildren();
  std::string out;
  // The generated sphere (no shared data) under the spot, 4k points: a second's bake.
  ASSERT_EQ(
      nestlight::test::runCli("make-scene diffrender -q -n 4k --width 48 --height 36 --bake-spp 4 "
                              "--shared-data " +
                                  dir.file("no-data") + " -o " + dir.file("room"),
                              &out),
      0)
      << out;
  const std::string scene = dir.file("room/scene.json");
  ASSERT_EQ(nestlight::test::runCli("bench diffrender " + scene +
                                        " --queries dit --presets low,med --samples 8,16 "
                                        "--cache 8 --runs 1 --reference-error 0.05 "
                                        "--reference-spp 256 -o " +
                                        dir.file("b"),
                                    &out),
            0)
      << out;
  EXPECT_NE(out.find("### Table 4"), std::string::npos) << out;
  EXPECT_NE(out.find("Target \"DIT and VCT beat EM"), std::string::npos) << out;
  const json j = json::parse(nestlight::test::readFile(dir.file("b/bench_diffrender.json")));
  // Rows: 1 query x 2 presets; N in {8, 16} x cache 8; one query's pair; the presets' materials;
  // the sweep's two N; one query's pick.
  EXPECT_EQ(rowsOf(j, "presets_times").size(), 2u);
  EXPECT_EQ(rowsOf(j, "presets_errors").size(), 2u);
  EXPECT_EQ(rowsOf(j, "cache").size(), 2u);
  EXPECT_EQ(rowsOf(j, "self_shadow").size(), 1u);
  EXPECT_EQ(rowsOf(j, "material").size(), 2u);
  EXPECT_EQ(rowsOf(j, "convergence").size(), 2u);
  ASSERT_EQ(rowsOf(j, "equal_time").size(), 1u);
  ASSERT_EQ(rowsOf(j, "equal_time_shade").size(), 1u);
  for (const json& r : rowsOf(j, "presets_errors")) {
    for (const char* key : {"composite_l2", "composite_l2_box4", "delta_l2", "object_l2", "rho_l2"})
      EXPECT_TRUE(finiteNonNegative(r[key])) << key << ": " << r.dump();
    EXPECT_TRUE(finiteNonNegative(r["rho_clamped"])) << "the method's counter: " << r.dump();
  }
  for (const json& r : rowsOf(j, "presets_times")) {
    EXPECT_TRUE(finiteNonNegative(r["pass_diffrender_shade_ms"])) << r.dump();
    EXPECT_TRUE(finiteNonNegative(r["impostor_build_ms"])) << r.dump();
    EXPECT_GT(r["frame_ms"].get<double>(), 0) << r.dump();
  }
  for (const json& r : rowsOf(j, "cache"))
    for (const char* key : {"delta_l2", "object_l2", "delta_l2_no_self_shadow", "shade_ms"})
      EXPECT_TRUE(finiteNonNegative(r[key])) << key << ": " << r.dump();
  for (const json& r : rowsOf(j, "material")) {
    EXPECT_TRUE(finiteNonNegative(r["floor_rho_error"])) << r.dump();
    EXPECT_GT(r["floor_albedo"].get<double>(), 0) << r.dump();
  }
  EXPECT_TRUE(std::filesystem::exists(dir.file("b/images/dit_med_rho.png")));
  EXPECT_TRUE(std::filesystem::exists(dir.file("b/images/dit_med_abs_dl.exr")));
  EXPECT_TRUE(std::filesystem::exists(dir.file("b/bench_diffrender.md")));
  EXPECT_TRUE(std::filesystem::exists(dir.file("b/bench_diffrender_cache.csv")));
  // The picks (budgets: DIT med's frame and shade pass times, and DIT med is the sweep's N = 16)
  // are within their budgets, and no larger N of the sweep is.
  for (const auto& [table, column] : std::vector<std::pair<std::string, std::string>>{
           {"equal_time", "frame_ms"}, {"equal_time_shade", "shade_ms"}}) {
    const json& pick = rowsOf(j, table).at(0);
    const double budget = pick.at("budget_ms").get<double>();
    ASSERT_TRUE(pick.at("samples").is_number()) << pick.dump();
    EXPECT_LE(pick.at("ms").get<double>(), budget) << pick.dump();
    for (const json& r : rowsOf(j, "convergence"))
      if (r.at("samples").get<int>() > pick.at("samples").get<int>())
        EXPECT_GT(r.at(column).get<double>(), budget) << table << ": " << r.dump();
  }
  EXPECT_TRUE(j.at("equal_time").at("dit_beats_em").is_null()) << "no em measured";

  // Bad options: errors naming the option, before anything renders.
  for (const auto& [args, option] :
       std::vector<std::pair<std::string, std::string>>{{"--queries dit,foo", "--queries"},
                                                        {"--presets ultra", "--presets"},
                                                        {"--samples 8,x", "--samples"},
                                                        {"--samples 0", "--samples"},
                                                        {"--cache 2000", "--cache"},
                                                        {"--tables presets,fig12", "--tables"},
                                                        {"--runs 0", "--runs"}}) {
    EXPECT_NE(nestlight::test::runCli(
                  "bench diffrender " + scene + " " + args + " -o " + dir.file("bad"), &out),
              0)
        << args;
    EXPECT_NE(out.find(option), std::string::npos) << args << ": " << out;
  }
}

}  // namespace
