// `bench gi` as a reader meets it: the time-to-error rule (interpolated where measured,
// extrapolated only along a clearly falling curve and not far beyond it), which methods and
// variants a scene lets apply (and why not), and the text table's columns.
#include "nestlight/bench/bench_gi.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "nestlight/bench/harness.h"
#include "nestlight/gi/methods.h"
#include "test_support.h"

namespace {

using nestlight::bench::ErrorPoint;
using nestlight::bench::timeToError;

// Points at 10, 20, 40, ... ms with the given errors.
std::vector<ErrorPoint> curve(const std::vector<double>& errors) {
  std::vector<ErrorPoint> c;
  double ms = 10;
  for (double e : errors) {
    c.push_back({ms, e, std::to_string(int(ms)) + " ms"});
    ms *= 2;
  }
  return c;
}

TEST(BenchGiTimeToError, InterpolatesWhereTheCurveCrossesTheTarget) {
  // 0.02 at 20 ms, 0.005 at 40 ms: 0.01 lies half-way in log error, so half-way in log time.
  const auto t = timeToError(curve({0.05, 0.02, 0.005}), 0.01);
  ASSERT_TRUE(t.ms);
  EXPECT_NEAR(*t.ms, std::sqrt(20.0 * 40.0), 1e-9);
  EXPECT_NE(t.how.find("interpolated"), std::string::npos) << t.how;
  EXPECT_EQ(*timeToError(curve({0.005, 0.002}), 0.01).ms, 10);
}

TEST(BenchGiTimeToError, ExtrapolatesAFallingCurveAlongItsFit) {
  // Monte Carlo: error ~ time^-1/2, from 0.08 at 10 ms to 0.02 at 160 ms. 0.01 needs 4x the
  // last time (640 ms), within 10x the longest measured.
  std::vector<double> e;
  for (int i = 0; i < 5; ++i) e.push_back(0.08 / std::sqrt(std::pow(2.0, i)));
  const auto t = timeToError(curve(e), 0.01);
  ASSERT_TRUE(t.ms) << t.how;
  EXPECT_NEAR(*t.ms, 640, 1e-6);
  ASSERT_TRUE(t.slope);
  EXPECT_NEAR(*t.slope, -0.5, 1e-9);
  EXPECT_NE(t.how.find("extrapolated"), std::string::npos);
  // The same curve to 0.001 would need 64000 ms, 400x the longest: not reached.
  const auto far = timeToError(curve(e), 0.001);
  EXPECT_FALSE(far.ms) << far.how;
  EXPECT_NE(far.how.find("beyond 10x"), std::string::npos) << far.how;
}

TEST(BenchGiTimeToError, AFlatOrRisingCurveIsNotReached) {
  // ibl (smc)'s case: error flat against time. Slopes -0.01 (flat) and +0.3 (rising) are both
  // above the -0.2 threshold.
  for (const auto& e :
       {std::vector<double>{0.05, 0.0497, 0.0494, 0.0491},
        std::vector<double>{0.05, 0.05 * std::pow(2, 0.3), 0.05 * std::pow(4, 0.3)}}) {
    const auto t = timeToError(curve(e), 0.01);
    EXPECT_FALSE(t.ms) << t.how;
    EXPECT_NE(t.how.find("not falling"), std::string::npos) << t.how;
  }
  // raster's case: a quality that costs no time has no trend to extrapolate.
  const auto same = timeToError({{5, 0.2, "256 texels"}, {5, 0.19, "512 texels"}}, 0.01);
  EXPECT_FALSE(same.ms) << same.how;
  // vpl on llvmpipe: errors fall a little while the time hardly grows (2800 to 3125 ms): a
  // steep-looking slope (-0.24) from a span of 1.1x in time is not extrapolated.
  const auto narrow =
      timeToError({{2800, 0.1152, "64"}, {2906, 0.1199, "256"}, {3125, 0.1133, "1024"}}, 0.1);
  EXPECT_FALSE(narrow.ms) << narrow.how;
  EXPECT_NE(narrow.how.find("no trend in time"), std::string::npos) << narrow.how;
  EXPECT_FALSE(timeToError({{5, 0.2, "a"}}, 0.01).ms);
}

TEST(BenchGiTimeToError, NoiseWithoutTrendIsNotExtrapolated) {
  // Falling at first, then scattered about 0.04: the last three points decide, and they do not
  // fall as clearly as the rule asks (their fitted slope is about -0.08, above -0.2).
  const auto noisy = timeToError(curve({0.2, 0.1, 0.04, 0.05, 0.035, 0.045}), 0.01);
  EXPECT_FALSE(noisy.ms) << noisy.how;
  // Noisy but falling as time^-1/2 (+-10%): extrapolated, near the noiseless 4x the last time.
  std::vector<double> e;
  const double wobble[] = {1.1, 0.9, 1.08, 0.93, 1.0};
  for (int i = 0; i < 5; ++i) e.push_back(wobble[i] * 0.08 / std::sqrt(std::pow(2.0, i)));
  const auto t = timeToError(curve(e), 0.01);
  ASSERT_TRUE(t.ms) << t.how;
  EXPECT_GT(*t.ms, 400);
  EXPECT_LT(*t.ms, 1000);
}

TEST(BenchGiApplicability, IblNeedsAnEnvironment) {
  nestlight::gi::Scene room;  // a cornell-like room: scan points, no environment
  room.gi.mode = nestlight::gi::RadianceMode::RadianceCache;
  const auto* ibl = nestlight::gi::findMethod("ibl");
  ASSERT_NE(ibl, nullptr);
  const std::string why = nestlight::gi::whyNotApplicable(*ibl, room);
  EXPECT_NE(why.find("no environment"), std::string::npos) << why;
  for (const auto& v : ibl->variants)  // the method's reason holds for every variant
    EXPECT_EQ(nestlight::gi::whyNotApplicable(*ibl, room, &v), why);
  room.environment = nestlight::gi::SceneEnvironment{};
  room.environment->constant = nestlight::gi::Rgb{1.0f};
  EXPECT_EQ(nestlight::gi::whyNotApplicable(*ibl, room), "");
  EXPECT_EQ(nestlight::gi::whyNotApplicable(*nestlight::gi::findMethod("raster"), room), "");
}

// projection's "1 bounce" (max_bounces 2: no gather at the points of S) differs only in the albedo
// mode, "no glossy-to-glossy" only with a glossy mesh; its sampling and image-space variants apply
// everywhere.
TEST(BenchGiApplicability, ProjectionBounceVariantOnlyInTheAlbedoMode) {
  nestlight::gi::Scene room;
  room.gi.mode = nestlight::gi::RadianceMode::RadianceCache;
  const auto* p = nestlight::gi::findMethod("projection");
  ASSERT_NE(p, nullptr);
  std::vector<std::string> names;
  for (const auto& v : p->variants) {
    names.push_back(v.name);
    const std::string why = nestlight::gi::whyNotApplicable(*p, room, &v);
    if (v.name == "1 bounce")
      EXPECT_NE(why.find("radiance-cache"), std::string::npos) << why;
    else if (v.name == "no glossy-to-glossy")
      EXPECT_NE(why.find("no glossy mesh"), std::string::npos) << why;
    else
      EXPECT_EQ(why, "") << v.name;
  }
  EXPECT_EQ(names,
            (std::vector<std::string>{"random", "splat 1", "splat 2", "splat 3", "every pixel",
                                      "grid", "1 bounce", "no glossy-to-glossy"}));
  room.gi.mode = nestlight::gi::RadianceMode::Albedo;
  nestlight::gi::Material glossy;
  glossy.type = nestlight::gi::MaterialType::GGX;
  room.materials.push_back(glossy);
  room.meshes.push_back(nestlight::gi::SceneMesh{});
  room.meshes.back().material = 0;
  for (const auto& v : p->variants) EXPECT_EQ(nestlight::gi::whyNotApplicable(*p, room, &v), "");
}

TEST(BenchGiApplicability, VplBouncesMatterOnlyWhereLightCanBounceOn) {
  nestlight::gi::Scene room;
  room.gi.mode = nestlight::gi::RadianceMode::RadianceCache;
  const auto* vpl = nestlight::gi::findMethod("vpl");
  ASSERT_NE(vpl, nullptr);
  auto reasonOf = [&](const std::string& variant) {
    for (const auto& v : vpl->variants)
      if (v.name == variant) return nestlight::gi::whyNotApplicable(*vpl, room, &v);
    ADD_FAILURE() << "no vpl variant " << variant;
    return std::string();
  };
  // Radiance cache without meshes: light ends at the first scan point it reaches.
  for (const char* v : {"1 bounce", "2 bounces", "3 bounces"})
    EXPECT_NE(reasonOf(v).find("radiance-cache"), std::string::npos) << v;
  EXPECT_EQ(reasonOf("exact visibility"), "");
  EXPECT_EQ(nestlight::gi::whyNotApplicable(*vpl, room), "");
  // One convex closed mesh (the generated room's sphere; here an octahedron) cannot light
  // itself: still the same image. The octahedron with its top vertex pushed through to below
  // its middle is closed but concave, and lights itself: bounces matter. So do two meshes.
  nestlight::test::TempDir t;
  const std::string faces =
      "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";
  nestlight::test::writeFile(t.file("convex.obj"),
                             "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n" + faces);
  nestlight::test::writeFile(
      t.file("concave.obj"),
      "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 -0.5\nv 0 0 -1\n" + faces);
  room.meshes.emplace_back();
  room.meshes[0].path = t.file("convex.obj");
  EXPECT_NE(reasonOf("2 bounces").find("convex"), std::string::npos) << reasonOf("2 bounces");
  room.meshes[0].path = t.file("concave.obj");
  EXPECT_EQ(reasonOf("2 bounces"), "");
  room.meshes[0].path = t.file("convex.obj");
  room.meshes.push_back(room.meshes[0]);
  EXPECT_EQ(reasonOf("2 bounces"), "");
  // In the albedo mode scan points reflect too.
  room.meshes.clear();
  room.gi.mode = nestlight::gi::RadianceMode::Albedo;
  EXPECT_EQ(reasonOf("2 bounces"), "");
}

TEST(BenchGiApplicability, PbgiWithoutMeshesIsItsNoMeshesVariant) {
  nestlight::gi::Scene room;
  const auto* pbgi = nestlight::gi::findMethod("pbgi");
  ASSERT_NE(pbgi, nullptr);
  for (const auto& v : pbgi->variants) {
    const std::string why = nestlight::gi::whyNotApplicable(*pbgi, room, &v);
    EXPECT_EQ(why.empty(), v.name != "no meshes") << v.name << ": " << why;
  }
}

// The column where each cell starts, in code points, found by walking the line's cells.
TEST(BenchGiTable, ColumnsAlignInEveryRow) {
  const std::vector<std::vector<std::string>> rows = {{"method", "variant", "median ms", "rays/s"},
                                                      {"reference", "—", "1234.5", "12.3 M"},
                                                      {"vpl", "exact visibility", "3.2", "—"},
                                                      {"ibl", "bsdf sampling", "98765.4", "—"}};
  const std::string text = nestlight::bench::alignedTable(rows, {false, false, true, true});
  std::vector<std::string> lines;
  for (size_t a = 0, b; (b = text.find('\n', a)) != std::string::npos; a = b + 1)
    lines.push_back(text.substr(a, b - a));
  ASSERT_EQ(lines.size(), rows.size() + 1);  // and the header's rule
  auto width = [](const std::string& s) {
    size_t n = 0;
    for (char c : s) n += (static_cast<unsigned char>(c) & 0xc0) != 0x80;
    return n;
  };
  // Right-aligned last column: every line ends at the same code point; each cell of a
  // left-aligned column starts where the header's does.
  for (const std::string& l : lines) EXPECT_EQ(width(l), width(lines[0])) << l;
  const size_t variantAt = width(lines[0].substr(0, lines[0].find("variant")));
  for (size_t r = 1; r < rows.size(); ++r) {
    const std::string& l = lines[r + 1];
    EXPECT_EQ(width(l.substr(0, l.find(rows[r][1]))), variantAt) << l;
    // The right-aligned "median ms" cells end at the same column as its header.
    const size_t headerEnd = width(lines[0].substr(0, lines[0].find("median ms") + 9));
    EXPECT_EQ(width(l.substr(0, l.find(rows[r][2]) + rows[r][2].size())), headerEnd) << l;
  }
}

}  // namespace
