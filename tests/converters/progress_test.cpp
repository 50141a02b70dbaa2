// The convert progress printer (nestlight/converters/progress.h) on a clock the test moves: no
// line before a rate can be measured, one unit per phase, and an ETA across the planned phases.
#include "nestlight/converters/progress.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

using nestlight::Progress;
using nestlight::ProgressMode;

namespace {

// A Progress writing to a temporary file, on a clock set by the test.
struct Printer {
  explicit Printer(ProgressMode mode)
      : file(std::tmpfile()), progress(mode, file, [this] { return seconds; }) {}
  ~Printer() { std::fclose(file); }
  std::string text() {
    std::fflush(file);
    std::string s;
    std::rewind(file);
    char buf[4096];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, file)) > 0) s.append(buf, n);
    return s;
  }
  // The terminal's lines: each \r starts one over.
  std::vector<std::string> lines() {
    std::vector<std::string> out;
    std::string cur;
    for (char c : text()) {
      if (c == '\r' || c == '\n') {
        if (!cur.empty()) out.push_back(cur);
        cur.clear();
      } else {
        cur += c;
      }
    }
    if (!cur.empty()) out.push_back(cur);
    for (auto& l : out)
      if (l.rfind("\033[K", 0) == 0) l = l.substr(3);
    return out;
  }
  std::FILE* file;
  double seconds = 0;
  Progress progress;
};

}  // namespace

TEST(Progress, NothingIsPrintedUntilARateCanBeMeasured) {
  Printer p(ProgressMode::Terminal);
  p.progress.begin("count", 1000, "bytes");
  EXPECT_EQ(p.text(), "");  // no "0.0%  0.00 M bytes/s  ETA 0 s" opening the phase
  p.seconds = 0.1;
  p.progress.advance(100, 10);
  EXPECT_EQ(p.text(), "");  // too soon for a rate
  p.seconds = 1;
  p.progress.advance(400, 40'000'000);
  const auto lines = p.lines();
  ASSERT_EQ(lines.size(), 1u) << p.text();
  EXPECT_NE(lines[0].find("count"), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find("50.0%"), std::string::npos) << lines[0];
  // A phase that reads input counts bytes and shows points, from its first line to its last.
  EXPECT_NE(lines[0].find("40.00 M points/s"), std::string::npos) << lines[0];
  EXPECT_EQ(lines[0].find("bytes"), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find("ETA 1 s"), std::string::npos) << lines[0];
  p.seconds = 1.1;  // within a quarter second of the last line: none
  p.progress.advance(500, 40'000'000);
  p.seconds = 2;
  p.progress.end();
  const auto all = p.lines();
  ASSERT_EQ(all.size(), 2u) << p.text();
  EXPECT_NE(all[1].find("100.0%"), std::string::npos) << all[1];
  EXPECT_NE(all[1].find("40.00 M points/s"), std::string::npos) << all[1];
  EXPECT_NE(all[1].find("in 2.0 s"), std::string::npos) << all[1];
  for (const auto& l : all) EXPECT_EQ(l.find("  0.00 M"), std::string::npos) << l;
}

TEST(Progress, TheEtaSpansThePlannedPhases) {
  Printer p(ProgressMode::Terminal);
  // bounds is skipped (the headers declare them): it drops out of the plan.
  p.progress.plan({{"bounds", 1}, {"count", 1}, {"distribute", 2}, {"index", 2}});
  p.progress.begin("count", 100, "bytes");
  p.seconds = 1;
  p.progress.advance(50, 500);
  // count: 1 s done, 1 s to go, so 2 s for a share of 1; distribute and index: 4 shares, 8 s.
  auto lines = p.lines();
  ASSERT_EQ(lines.size(), 1u) << p.text();
  EXPECT_EQ(lines[0].rfind("[1/3] count", 0), 0u) << lines[0];
  EXPECT_NE(lines[0].find("ETA 9 s overall"), std::string::npos) << lines[0];
  p.seconds = 2;
  p.progress.advance(50, 500);
  p.progress.end();
  EXPECT_NE(p.lines().back().find("[1/3] count      100.0%  500.0 points/s  in 2.0 s"),
            std::string::npos)
      << p.text();
  // distribute: measured at 4 s for its share of 2 after count took 2 s for 1 (3 s per share
  // over both), index's share of 2 to come.
  p.progress.begin("distribute", 100, "bytes");
  p.seconds = 4;
  p.progress.advance(50, 500);
  lines = p.lines();
  EXPECT_EQ(lines.back().rfind("[2/3] distribute", 0), 0u) << lines.back();
  // 2 s left in distribute; (2 + 4) s over 3 shares is 2 s a share: index 4 s more.
  EXPECT_NE(lines.back().find("ETA 6 s overall"), std::string::npos) << lines.back();
  p.seconds = 6;
  p.progress.end();
  // A phase in other units shows its own, the rate it measured, and no points.
  p.progress.begin("index", 3, "levels");
  p.seconds = 7;
  p.progress.advance(1);
  lines = p.lines();
  EXPECT_EQ(lines.back().rfind("[3/3] index", 0), 0u) << lines.back();
  EXPECT_NE(lines.back().find("1.0 levels/s"), std::string::npos) << lines.back();
  EXPECT_NE(lines.back().find("ETA 2 s overall"), std::string::npos) << lines.back();
}

TEST(Progress, JsonLinesCarryTheOverallEtaAndNoEmptyOpening) {
  Printer p(ProgressMode::Json);
  p.progress.plan({{"count", 1}, {"distribute", 3}});
  p.progress.begin("count", 100, "bytes");
  p.seconds = 1;
  p.progress.advance(10, 100);  // under JSON's 2 s interval: nothing yet
  EXPECT_EQ(p.text(), "");
  p.seconds = 2.5;
  p.progress.advance(40, 400);
  p.seconds = 5;
  p.progress.advance(50, 500);
  p.progress.end();
  std::istringstream in(p.text());
  std::vector<nlohmann::json> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(nlohmann::json::parse(l));
  ASSERT_EQ(lines.size(), 3u) << p.text();
  for (const auto& j : lines) {
    EXPECT_GT(j["done"].get<uint64_t>(), 0u) << j;
    EXPECT_EQ(j["phase"], "count");
    EXPECT_EQ(j["step"], 1);
    EXPECT_EQ(j["steps"], 2);
  }
  // 50% at 2.5 s: 2.5 s left in count, then 3 shares at 5 s a share.
  EXPECT_DOUBLE_EQ(lines[0]["phase_eta"].get<double>(), 2.5);
  EXPECT_DOUBLE_EQ(lines[0]["eta"].get<double>(), 17.5);
  EXPECT_EQ(lines[2]["final"], true);
  EXPECT_FALSE(lines[2].contains("eta"));
  EXPECT_EQ(lines[2]["points"], 1000);
}
