// Speed-against-error charts (SVG, and the same drawn into a PNG): one colour per method and one
// marker per variant, point labels that never overlap, well-formed XML (balanced tags, escaped
// text), one marker per drawable point, decade ticks on log axes, and the awkward inputs (one
// point, equal values, zero and negative values on log axes, NaN) drawn without NaN coordinates and
// explained.
#include "nestlight/gi/plot.h"

#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "nestlight/gi/hdr_image.h"
#include "test_support.h"

using namespace nestlight::gi;
using nestlight::test::errorOf;
using nestlight::test::readFile;
using nestlight::test::TempDir;

namespace {

size_t count(const std::string& s, const std::string& what) {
  size_t n = 0;
  for (size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + what.size())) ++n;
  return n;
}

// A small XML checker: every start tag is closed in order, the root is <svg>, nothing but
// whitespace outside it, and every '&' starts one of the five predefined entities. Returns the
// first fault, or "" when there is none.
std::string xmlFault(const std::string& s) {
  std::vector<std::string> open;
  bool rootSeen = false;
  size_t i = 0;
  while (i < s.size()) {
    if (s[i] == '&') {
      bool ok = false;
      for (const char* e : {"&amp;", "&lt;", "&gt;", "&quot;", "&apos;"})
        ok = ok || s.compare(i, std::strlen(e), e) == 0;
      if (!ok) return "bare & at " + std::to_string(i);
    }
    if (s[i] == '>') return "bare > at " + std::to_string(i);  // we escape it in text too
    if (s[i] != '<') {
      if (open.empty() && !std::isspace(static_cast<unsigned char>(s[i])))
        return "text outside the root";
      ++i;
      continue;
    }
    if (s.compare(i, 2, "<?") == 0) {
      size_t end = s.find("?>", i);
      if (end == std::string::npos) return "unterminated <?";
      i = end + 2;
      continue;
    }
    if (s.compare(i, 4, "<!--") == 0) {
      size_t end = s.find("-->", i);
      if (end == std::string::npos) return "unterminated comment";
      i = end + 3;
      continue;
    }
    size_t end = i + 1;
    char quote = 0;
    for (; end < s.size(); ++end) {  // '>' inside a quoted attribute value does not end the tag
      if (quote) {
        if (s[end] == quote)
          quote = 0;
        else if (s[end] == '<')
          return "< inside an attribute value";
      } else if (s[end] == '"' || s[end] == '\'') {
        quote = s[end];
      } else if (s[end] == '>') {
        break;
      }
    }
    if (end >= s.size()) return "unterminated tag at " + std::to_string(i);
    std::string tag = s.substr(i + 1, end - i - 1);
    i = end + 1;
    if (tag.empty()) return "empty tag";
    if (tag[0] == '/') {
      std::string name = tag.substr(1);
      if (open.empty() || open.back() != name)
        return "</" + name + "> closes " + (open.empty() ? "nothing" : open.back());
      open.pop_back();
      continue;
    }
    const bool selfClosing = tag.back() == '/';
    std::string name = tag.substr(0, tag.find_first_of(" \t\n/"));
    if (open.empty()) {
      if (rootSeen) return "second root element <" + name + ">";
      if (name != "svg") return "root is <" + name + ">";
      rootSeen = true;
    }
    if (!selfClosing) open.push_back(name);
  }
  if (!open.empty()) return "<" + open.back() + "> never closed";
  if (!rootSeen) return "no root";
  return "";
}

std::vector<PlotSeries> speedError() {
  return {{"VPL+ISM", {{2.0, 0.31, "64 VPL"}, {5.5, 0.12, "256 VPL"}, {19.0, 0.05, "1024 VPL"}}},
          {"PBGI", {{1.2, 0.2, ""}, {3.0, 0.08, ""}}},
          {"path tracer", {{400.0, 0.004, "4096 spp"}}}};
}

}  // namespace

TEST(Plot, WellFormedWithEveryNameAndOneMarkerPerPoint) {
  const std::string svg =
      svgPlot("Speed against error", "ms per frame", "relMSE", speedError(), true, true);
  EXPECT_EQ(xmlFault(svg), "") << svg;
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_EQ(count(svg, "class=\"marker\""), 6u);
  EXPECT_EQ(count(svg, "class=\"legend-marker\""), 3u);
  EXPECT_EQ(count(svg, "<polyline"), 2u);  // a single point draws no line
  for (const char* s : {"VPL+ISM", "PBGI", "path tracer", "Speed against error", "ms per frame",
                        "relMSE", "256 VPL", "4096 spp"})
    EXPECT_NE(svg.find(s), std::string::npos) << s;
  EXPECT_EQ(svg.find("nan"), std::string::npos);
  EXPECT_EQ(svg.find("inf"), std::string::npos);
  EXPECT_EQ(svg.find("left out"), std::string::npos);  // nothing was skipped
}

TEST(Plot, LogAxesHaveDecadeTicks) {
  // x from 1 to 1000: decades 10^0 .. 10^3, labelled 1, 10, 10^2, 10^3.
  const std::string svg = svgPlot("t", "x", "y", {{"s", {{1, 0.5}, {1000, 2}}}}, true, false);
  EXPECT_EQ(xmlFault(svg), "");
  EXPECT_NE(svg.find(">1</text>"), std::string::npos) << svg;
  EXPECT_NE(svg.find(">10</text>"), std::string::npos);
  EXPECT_NE(svg.find(">2</tspan>"), std::string::npos);
  EXPECT_NE(svg.find(">3</tspan>"), std::string::npos);
  EXPECT_EQ(svg.find(">4</tspan>"), std::string::npos);
  // Linear y from 0.5 to 2: about six steps of a nice size (0.2 here), printed without the
  // residue of 3 * 0.2 = 0.6000000000000001.
  for (const char* t : {">0.4</text>", ">0.6</text>", ">1.2</text>", ">2</text>"})
    EXPECT_NE(svg.find(t), std::string::npos) << t;
}

TEST(Plot, ZeroNegativeAndNonFinitePointsAreSkippedAndExplained) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<PlotSeries> s = {
      {"a", {{0, 1}, {1, -1}, {10, 0.1}, {100, 0.01}, {nan, 1}, {1, inf}}}};
  const std::string svg = svgPlot("t", "x", "y", s, true, true);
  EXPECT_EQ(xmlFault(svg), "") << svg;
  EXPECT_EQ(count(svg, "class=\"marker\""), 2u);
  EXPECT_NE(svg.find("2 points left out: zero or negative values cannot be drawn on a log axis"),
            std::string::npos)
      << svg;
  EXPECT_NE(svg.find("2 points left out: not finite"), std::string::npos);
  // On linear axes zero and negative values are fine; only the non-finite go.
  const std::string lin = svgPlot("t", "x", "y", s, false, false);
  EXPECT_EQ(count(lin, "class=\"marker\""), 4u);
  EXPECT_EQ(lin.find("log axis"), std::string::npos);
  EXPECT_EQ(lin.find("nan"), std::string::npos);
}

TEST(Plot, SinglePointEqualValuesAndNoDataStillMakeAChart) {
  for (bool logAxes : {false, true}) {
    for (const auto& s :
         std::vector<std::vector<PlotSeries>>{{{"one", {{5, 5}}}},
                                              {{"equal", {{3, 0.1}, {3, 0.1}, {3, 0.1}}}},
                                              {{"decade", {{10, 100}}}},
                                              {{"zero", {{0, 0}}}},
                                              {},
                                              {{"empty", {}}}}) {
      const std::string svg = svgPlot("t", "x", "y", s, logAxes, logAxes);
      EXPECT_EQ(xmlFault(svg), "") << svg;
      EXPECT_EQ(svg.find("nan"), std::string::npos) << svg;
      EXPECT_EQ(svg.find("inf"), std::string::npos) << svg;
      size_t points = 0;
      for (const auto& ser : s) points += ser.points.size();
      const bool nothingDrawable = points == 0 || (logAxes && s[0].name == "zero");
      EXPECT_EQ(count(svg, "class=\"marker\""), nothingDrawable ? 0 : points) << svg;
      EXPECT_EQ(svg.find("No point to draw.") != std::string::npos, nothingDrawable) << svg;
    }
  }
}

TEST(Plot, TextIsEscaped) {
  std::vector<PlotSeries> s = {{"a<b & \"c\" 'd'>", {{1, 2, "<label&>"}}}};
  const std::string svg = svgPlot("T<&>", "x\x01y", "y>", s, false, false);
  EXPECT_EQ(xmlFault(svg), "") << svg;
  EXPECT_NE(svg.find("a&lt;b &amp; &quot;c&quot; &apos;d&apos;&gt;"), std::string::npos) << svg;
  EXPECT_NE(svg.find("&lt;label&amp;&gt;"), std::string::npos);
  EXPECT_NE(svg.find("T&lt;&amp;&gt;"), std::string::npos);
  EXPECT_NE(svg.find("x?y"), std::string::npos);  // U+0001 is not allowed in XML 1.0
  EXPECT_EQ(svg.find("<b"), std::string::npos);
  EXPECT_EQ(xmlEscape("plain text"), "plain text");
}

TEST(Plot, ManySeriesCycleStylesAndHugeRangesStayFinite) {
  std::vector<PlotSeries> s;
  for (int i = 0; i < 12; ++i)
    s.push_back(
        {"series " + std::to_string(i), {{1e-300 * (i + 1), 1e300 / (i + 1)}, {1e300, 1e-300}}});
  for (bool logAxes : {false, true}) {
    const std::string svg = svgPlot("t", "x", "y", s, logAxes, logAxes);
    EXPECT_EQ(xmlFault(svg), "");
    EXPECT_EQ(count(svg, "class=\"marker\""), 24u);
    EXPECT_EQ(count(svg, "class=\"legend-marker\""), 12u);
    EXPECT_EQ(svg.find("nan"), std::string::npos);
  }
}

TEST(Plot, WriteSvgPlotWritesTheSameTextOrThrowsNamingThePath) {
  TempDir t;
  const auto series = speedError();
  writeSvgPlot(t.file("p.svg"), "t", "x", "y", series, true, false);
  EXPECT_EQ(readFile(t.file("p.svg")), svgPlot("t", "x", "y", series, true, false));
  EXPECT_FALSE(std::filesystem::exists(t.file("p.svg.partial")));
  const nestlight::Error e =
      errorOf([&] { writeSvgPlot(t.file("missing/p.svg"), "t", "x", "y", series, 0, 0); });
  EXPECT_NE(e.file().find("missing/p.svg"), std::string::npos) << e.what();
}

TEST(Plot, OneColourPerGroupAndOneMarkerPerSeriesWithinIt) {
  // bench gi's case: 6 methods, up to 6 variants each; series of one method share its colour.
  std::vector<PlotSeries> s;
  const int variants[] = {1, 1, 1, 5, 6, 5};
  for (int m = 0; m < 6; ++m)
    for (int v = 0; v < variants[m]; ++v)
      s.push_back({"m" + std::to_string(m) + " v" + std::to_string(v),
                   {{1.0 + m, 0.1 + 0.01 * v}},
                   "m" + std::to_string(m)});
  const PlotLayout L = plotLayout(s, true, true);
  ASSERT_EQ(L.styles.size(), s.size());
  for (size_t a = 0; a < s.size(); ++a)
    for (size_t b = a + 1; b < s.size(); ++b) {
      const bool sameGroup = s[a].group == s[b].group;
      EXPECT_EQ(L.styles[a].colour == L.styles[b].colour, sameGroup) << a << " " << b;
      // Within a method each variant has its own marker (6 variants, 8 shapes).
      if (sameGroup) EXPECT_NE(L.styles[a].marker, L.styles[b].marker) << a << " " << b;
    }
  EXPECT_GE(plotMarkerCount(), 6);
  // The SVG draws what the layout says: every series' colour appears in it.
  const std::string svg = svgPlot("t", "x", "y", s, true, true);
  for (const auto& st : L.styles) EXPECT_NE(svg.find(st.colour), std::string::npos);
}

TEST(Plot, PointLabelsNeverOverlapOnACrowdedChart) {
  // 12 series of 5 points crowded into one decade, every point labelled: far more labels than
  // free room. Placed labels must not overlap each other; the rest are counted and noted.
  std::vector<PlotSeries> s;
  for (int i = 0; i < 12; ++i) {
    PlotSeries ps{"s" + std::to_string(i), {}, "g" + std::to_string(i % 4)};
    for (int k = 0; k < 5; ++k)
      ps.points.push_back(
          {10 + 3.0 * k + 0.4 * i, 0.05 + 0.01 * k + 0.002 * i, std::to_string(1 << k) + " spp"});
    s.push_back(ps);
  }
  const PlotLayout L = plotLayout(s, true, true);
  EXPECT_EQ(L.labels.size() + L.labelsLeftOut, 60u);
  EXPECT_GT(L.labels.size(), 5u);  // some room was found
  for (size_t a = 0; a < L.labels.size(); ++a) {
    EXPECT_LT(L.labels[a].box.x0, L.labels[a].box.x1);
    for (size_t b = a + 1; b < L.labels.size(); ++b)
      EXPECT_FALSE(L.labels[a].box.overlaps(L.labels[b].box))
          << L.labels[a].text << " and " << L.labels[b].text;
  }
  const std::string svg = svgPlot("t", "x", "y", s, true, true);
  EXPECT_EQ(count(svg, "class=\"point-label\""), L.labels.size());
  if (L.labelsLeftOut)
    EXPECT_NE(svg.find("point labels left out where they would overlap"), std::string::npos);
}

TEST(Plot, PngIsWrittenAndDecodesWithTheSeriesColours) {
  TempDir t;
  std::vector<PlotSeries> s = {{"a", {{1, 0.5, "1 spp"}, {10, 0.1, "16 spp"}}, "a"},
                               {"b", {{2, 0.3}, {20, 0.05}}, "b"}};
  writePngPlot(t.file("p.png"), "title", "x (ms)", "error", s, true, true);
  const HdrImage img = readPng(t.file("p.png"));
  const PlotLayout L = plotLayout(s, true, true);
  EXPECT_EQ(img.width, int(L.width));
  EXPECT_EQ(img.height, int(L.height));
  // The first series' colour (#0072B2 = 0, 114, 178) is drawn somewhere (its markers and line),
  // and so is black text; the background is white.
  auto has = [&](float r, float g, float b) {
    for (size_t p = 0; p < img.pixels(); ++p)
      if (std::abs(img.rgb[3 * p] - r) < 0.02f && std::abs(img.rgb[3 * p + 1] - g) < 0.02f &&
          std::abs(img.rgb[3 * p + 2] - b) < 0.02f)
        return true;
    return false;
  };
  EXPECT_TRUE(has(0, 114 / 255.f, 178 / 255.f));
  EXPECT_TRUE(has(213 / 255.f, 94 / 255.f, 0));  // the second's, #D55E00
  EXPECT_TRUE(has(0, 0, 0));
  EXPECT_TRUE(has(1, 1, 1));
  EXPECT_FALSE(std::filesystem::exists(t.file("p.png.partial")));
}
