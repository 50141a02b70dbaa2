// XYZ/PTS/TXT reader: columns guessed and named, PTS counts, separators and comments, and the
// errors a hand-edited text file produces, each checked value by value.
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "nestlight/converters/reader.h"
#include "nestlight/octree/error.h"
#include "test_support.h"

namespace nestlight {
namespace {

using test::anyContains;
using test::attrAt;
using test::errorOf;
using test::Points;
using test::readAll;

std::unique_ptr<PointReader> open(const std::string& text, const std::string& columns = "",
                                  bool lenient = false) {
  ReadOptions o;
  o.columns = columns;
  o.lenient = lenient;
  return openXyz(memorySource("scan.xyz", std::vector<uint8_t>(text.begin(), text.end())), o);
}

std::vector<std::string> names(const PointLayout& l) {
  std::vector<std::string> n;
  for (auto& a : l.attributes()) n.push_back(a.name);
  return n;
}

TEST(XyzReader, GuessesColumnsFromTheirCount) {
  struct Case {
    std::string line;
    std::vector<std::string> attrs;
    int rgbBits;
  } cases[] = {
      {"1 2 3", {}, 0},
      {"1 2 3 400", {"intensity"}, 0},
      {"1 2 3 10 20 30", {"rgb"}, 8},
      {"1 2 3 400 10 20 30", {"intensity", "rgb"}, 8},
      {"1 2 3 10 20 30 0 0.6 0.8", {"rgb", "normal"}, 8},
      {"1 2 3 400 10 20 30 0 0.6 0.8", {"intensity", "rgb", "normal"}, 8},
  };
  for (const auto& c : cases) {
    std::string text = c.line;
    text += '\n';
    text += text;
    auto r = open(text);
    EXPECT_EQ(names(r->header().layout), c.attrs) << c.line;
    EXPECT_EQ(r->header().rgbBits, c.rgbBits);
    EXPECT_EQ(r->header().details["columnsFrom"], "guessed");
    EXPECT_FALSE(r->header().declaredPoints.has_value());
    Points p = readAll(*r);
    ASSERT_EQ(p.size(), 2u);
    EXPECT_EQ(p.xyz, (std::vector<double>{1, 2, 3, 1, 2, 3}));
    if (r->header().layout.has("intensity")) {
      EXPECT_EQ(attrAt<uint16_t>(p, *r, 1, "intensity"), 400);
    }
    if (r->header().layout.has("rgb")) {
      EXPECT_EQ(attrAt<uint16_t>(p, *r, 1, "rgb", 0), 10 * 257);
      EXPECT_EQ(attrAt<uint16_t>(p, *r, 1, "rgb", 2), 30 * 257);
    }
    if (r->header().layout.has("normal")) {
      EXPECT_EQ(attrAt<float>(p, *r, 1, "normal", 1), 0.6f);
      EXPECT_EQ(attrAt<float>(p, *r, 1, "normal", 2), 0.8f);
    }
  }
}

TEST(XyzReader, UnguessableColumnsAskForThem) {
  Error e = errorOf([] { open("1 2 3 4 5\n"); });
  EXPECT_EQ(e.file(), "scan.xyz");
  EXPECT_EQ(e.position(), "line 1");
  EXPECT_NE(e.reason().find("--columns"), std::string::npos);
  // Six columns guess colour; a first line whose "colour" is a fraction contradicts the guess.
  Error n = errorOf([] { open("# normals\n1 2 3 0 0.6 0.8\n"); });
  EXPECT_EQ(n.position(), "line 2");
  EXPECT_NE(n.reason().find("'0.6'"), std::string::npos) << n.what();
  EXPECT_NE(n.reason().find("--columns"), std::string::npos);
}

TEST(XyzReader, ExplicitColumns) {
  auto r = open(
      "10 20 30 skipped 7 65535 0 1000 2 0.5\n"
      "-1 -2 -3 x 8 1 2 3 255 -0.25\n",
      "x,y,z,_,intensity,R,G,B,classification,reflectance");
  const PointLayout& l = r->header().layout;
  EXPECT_EQ(names(l),
            (std::vector<std::string>{"intensity", "rgb", "classification", "reflectance"}));
  EXPECT_EQ(l[0].type, ScalarType::U16);
  EXPECT_EQ(l[1].type, ScalarType::U16);
  EXPECT_EQ(l[1].components, 3u);
  EXPECT_EQ(l[2].type, ScalarType::U8);
  EXPECT_EQ(l[3].type, ScalarType::F32);
  EXPECT_EQ(r->header().rgbBits, 16);
  EXPECT_EQ(r->header().details["columns"], "x,y,z,_,intensity,R,G,B,classification,reflectance");
  Points p = readAll(*r);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p.xyz, (std::vector<double>{10, 20, 30, -1, -2, -3}));
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 0, "intensity"), 7);
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 0, "rgb", 0), 65535);
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 0, "rgb", 2), 1000);
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 1, "rgb", 1), 2);
  EXPECT_EQ(attrAt<uint8_t>(p, *r, 1, "classification"), 255);
  EXPECT_EQ(attrAt<float>(p, *r, 1, "reflectance"), -0.25f);
  EXPECT_TRUE(r->warnings().empty());

  // Columns in any order: colour before position.
  auto q = open("255 0 128 1.5 2.5 3.5\n", "r,g,b,x,y,z");
  Points pq = readAll(*q);
  EXPECT_EQ(pq.xyz, (std::vector<double>{1.5, 2.5, 3.5}));
  EXPECT_EQ(attrAt<uint16_t>(pq, *q, 0, "rgb", 0), 65535);
  EXPECT_EQ(attrAt<uint16_t>(pq, *q, 0, "rgb", 2), 128 * 257);
  EXPECT_EQ(q->header().rgbBits, 8);
}

TEST(XyzReader, BadColumnSpecs) {
  for (const char* spec : {"x,y", "x,y,z,x", "x,y,z,r,g", "x,y,z,r,G,B", "x,y,z,nx,ny", "x,y,z,,i",
                           "x,y,z,rgb", "x,y,z,i,intensity", "x,y,z,r,r,g"}) {
    Error e = errorOf([&] { open("1 2 3 4 5 6\n", spec); });
    EXPECT_EQ(e.file(), "scan.xyz");
    EXPECT_NE(e.reason().find(spec), std::string::npos) << e.what();
  }
}

TEST(XyzReader, PtsCountHeader) {
  const std::string pts =
      "3\n"
      "0.5 1.5 2.5 -1200 255 128 0\n"
      "1 2 3 0 1 2 3\n"
      "4 5 6 2047 10 20 30\n";
  auto r = open(pts);
  EXPECT_EQ(r->header().declaredPoints, 3u);
  EXPECT_EQ(r->header().details["ptsCount"], 3);
  Points p = readAll(*r);
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p.xyz[0], 0.5);
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 2, "intensity"), 2047);
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 0, "rgb", 1), 128 * 257);
  // Leica's signed intensities do not fit uint16: clamped, and said so.
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 0, "intensity"), 0);
  ASSERT_EQ(r->warnings().size(), 1u);
  EXPECT_NE(r->warnings()[0].find("1 values of column 'i'"), std::string::npos);

  // Fewer points than declared: an error naming both counts, or a warning in lenient mode.
  std::string fewer = pts;
  fewer[0] = '5';
  Error e = errorOf([&] { readAll(*open(fewer)); });
  EXPECT_EQ(e.file(), "scan.xyz");
  EXPECT_NE(e.reason().find("declares 5 points but the file holds 3"), std::string::npos)
      << e.what();
  auto l = open(fewer, "", true);
  EXPECT_EQ(readAll(*l).size(), 3u);
  EXPECT_TRUE(anyContains(l->warnings(), "declares 5 points but the file holds 3"));

  // More points than declared: an error at the first extra line.
  std::string more = pts;
  more[0] = '2';
  Error m = errorOf([&] { readAll(*open(more)); });
  EXPECT_EQ(m.position(), "line 4");
  auto lm = open(more, "", true);
  EXPECT_EQ(readAll(*lm).size(), 3u);
  EXPECT_TRUE(anyContains(lm->warnings(), "declares 2 points but the file holds 3"));
}

TEST(XyzReader, CommasCommentsBlankLinesAndCrlf) {
  const std::string csv =
      "# exported by hand\r\n"
      "// another comment\r\n"
      "\r\n"
      "X,Y,Z,Red,Green,Blue\r\n"
      "1.25,2.5,-3,0,127,255\r\n"
      "   # indented comment\r\n"
      "4, 5, 6, 1, 2, 3\r\n"
      "\r\n";
  auto r = open(csv);
  EXPECT_EQ(r->header().details["separator"], "comma");
  EXPECT_EQ(r->header().details["headerLine"], "X,Y,Z,Red,Green,Blue");
  Points p = readAll(*r);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p.xyz, (std::vector<double>{1.25, 2.5, -3, 4, 5, 6}));
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 0, "rgb", 1), 127 * 257);
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 1, "rgb", 2), 3 * 257);
  EXPECT_EQ(r->bytesConsumed(), r->bytesTotal());

  // Rewind reads the same points again, skipping the comments and header line again.
  r->rewind();
  Points q = readAll(*r, 1);
  EXPECT_EQ(q.xyz, p.xyz);
  EXPECT_EQ(q.attrs, p.attrs);

  auto tabs = open("1\t2\t3\n\t4  5\t 6  \n");
  EXPECT_EQ(tabs->header().details["separator"], "whitespace");
  EXPECT_EQ(readAll(*tabs).xyz, (std::vector<double>{1, 2, 3, 4, 5, 6}));
}

TEST(XyzReader, BadTokenNamesLineAndToken) {
  Error e = errorOf([] { readAll(*open("# c\n1 2 3\n\n4 5 6\n7 8.0.1 9\n")); });
  EXPECT_EQ(e.file(), "scan.xyz");
  EXPECT_EQ(e.position(), "line 5");
  EXPECT_NE(e.reason().find("'8.0.1'"), std::string::npos) << e.what();
  EXPECT_NE(e.reason().find("column 2"), std::string::npos) << e.what();

  Error c = errorOf([] { readAll(*open("1 2 3 10 20 30\n1 2 3 10 twenty 30\n")); });
  EXPECT_EQ(c.position(), "line 2");
  EXPECT_NE(c.reason().find("'twenty'"), std::string::npos);
}

TEST(XyzReader, WrongNumberOfColumns) {
  Error e = errorOf([] { readAll(*open("1 2 3\n4 5 6 7\n8 9 10\n")); });
  EXPECT_EQ(e.position(), "line 2");
  EXPECT_NE(e.reason().find("expected 3 values"), std::string::npos) << e.what();
  EXPECT_NE(e.reason().find("found 4"), std::string::npos);
  Error f = errorOf([] { readAll(*open("1 2 3\n4 5\n8 9 10\n")); });
  EXPECT_EQ(f.position(), "line 2");

  // A cut last line: an error, or dropped with a warning in lenient mode.
  const std::string cut = "1 2 3\n4 5 6\n7 8";
  Error t = errorOf([&] { readAll(*open(cut)); });
  EXPECT_EQ(t.position(), "line 3");
  EXPECT_NE(t.reason().find("truncated"), std::string::npos);
  auto l = open(cut, "", true);
  EXPECT_EQ(readAll(*l).xyz, (std::vector<double>{1, 2, 3, 4, 5, 6}));
  ASSERT_EQ(l->warnings().size(), 1u);
  EXPECT_NE(l->warnings()[0].find("incomplete last line"), std::string::npos);
}

TEST(XyzReader, NanAndInfTokensPassThrough) {
  auto r = open("nan 1 2\n1 -inf 2\n1 2 Infinity\n1e999 -1e-999 3\n", "x,y,z");
  Points p = readAll(*r);
  ASSERT_EQ(p.size(), 4u);
  EXPECT_TRUE(std::isnan(p.xyz[0]));
  EXPECT_EQ(p.xyz[4], -std::numeric_limits<double>::infinity());
  EXPECT_EQ(p.xyz[8], std::numeric_limits<double>::infinity());
  EXPECT_EQ(p.xyz[9], std::numeric_limits<double>::infinity());  // beyond double: strtod's inf
  EXPECT_EQ(p.xyz[10], 0.0);
  EXPECT_TRUE(std::signbit(p.xyz[10]));

  // In an integer column, NaN cannot be stored: 0, counted in the warnings.
  auto c = open("1 2 3 nan\n1 2 3 70000\n", "x,y,z,intensity");
  Points pc = readAll(*c);
  EXPECT_EQ(attrAt<uint16_t>(pc, *c, 0, "intensity"), 0);
  EXPECT_EQ(attrAt<uint16_t>(pc, *c, 1, "intensity"), 65535);
  ASSERT_EQ(c->warnings().size(), 1u);
  EXPECT_NE(c->warnings()[0].find("2 values of column 'intensity'"), std::string::npos);
}

TEST(XyzReader, EmptyAndPointlessFiles) {
  Error e = errorOf([] { open(""); });
  EXPECT_EQ(e.file(), "scan.xyz");
  EXPECT_NE(e.reason().find("empty"), std::string::npos);
  EXPECT_NE(errorOf([] { open("# only a comment\n\n"); }).reason().find("no points"),
            std::string::npos);
  // With the columns named, or a PTS count of 0, a file without points is a cloud of none.
  PointBatch b;
  EXPECT_FALSE(open("# nothing\n", "x,y,z")->read(b, 100));
  auto z = open("0\n");
  EXPECT_EQ(z->header().declaredPoints, 0u);
  EXPECT_FALSE(z->read(b, 100));
}

TEST(XyzReader, OpenReaderByExtension) {
  test::TempDir dir;
  for (const char* ext : {".xyz", ".pts", ".txt", ".csv"}) {
    test::writeFile(dir.file(std::string("a") + ext), "2\n1 2 3\n4 5 6\n");
    auto r = openReader(dir.file(std::string("a") + ext));
    EXPECT_EQ(r->header().format, "xyz");
    EXPECT_EQ(r->header().declaredPoints, 2u);
    EXPECT_EQ(readAll(*r).size(), 2u);
  }
}

TEST(XyzReader, ManyPointsInBatches) {
  std::string text;
  for (int i = 0; i < 10000; ++i)
    text += std::to_string(i) + " " + std::to_string(-i - 1) + ".5 " + std::to_string(i % 7) +
            "e2 " + std::to_string(i % 256) + " 0 255\n";
  auto r = open(text);
  Points p = readAll(*r, 333);
  ASSERT_EQ(p.size(), 10000u);
  for (int i = 0; i < 10000; i += 997) {
    EXPECT_EQ(p.xyz[3 * i], i);
    EXPECT_EQ(p.xyz[3 * i + 1], -i - 1.5);
    EXPECT_EQ(p.xyz[3 * i + 2], (i % 7) * 100.0);
    EXPECT_EQ(attrAt<uint16_t>(p, *r, i, "rgb", 0), (i % 256) * 257);
  }
}

}  // namespace
}  // namespace nestlight
