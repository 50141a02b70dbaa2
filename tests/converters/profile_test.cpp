// `nestlight profile`: every point within W/2 of the line, from every level, with its distance
// along the line; the plots are written at the size asked.
#include "nestlight/converters/profile.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "nestlight/converters/point_writer.h"
#include "nestlight/converters/reader.h"
#include "test_support.h"

using namespace nestlight;
using nestlight::test::TempDir;
namespace fs = std::filesystem;

namespace profile_test {

// A wall 0.3 m thick, 40 m long and 12 m high (x across it, y along it) at national-grid
// coordinates, on a 1 mm grid, with a second, thinner wall crossing it: 80,000 points.
const double kEast = 512000, kNorth = 5401000;

void writeWall(const std::string& path) {
  SourceHeader h;
  h.format = "las";
  h.scale = Vec3d{0.001, 0.001, 0.001};
  h.offset = Vec3d{kEast, kNorth, 0};
  h.layout.add({"intensity", ScalarType::U16, 1, ""});
  // Its unit labels the plot's axes.
  h.crs = {{"wkt", R"(PROJCS["test grid",UNIT["metre",1]])"}};
  auto w = createWriter(path, h);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  PointBatch b;
  for (int i = 0; i < 80000; ++i) {
    double x, y;
    if (i % 4) {
      x = 10 + 0.3 * u(rng), y = 40 * u(rng);
    } else {
      x = 20 * u(rng), y = 20 + 0.1 * u(rng);
    }
    const double z = 12 * u(rng);
    b.xyz.insert(b.xyz.end(), {kEast + std::round(x * 1000) / 1000,
                               kNorth + std::round(y * 1000) / 1000, std::round(z * 1000) / 1000});
    const uint16_t in = uint16_t(i);
    b.attrs.insert(b.attrs.end(), {uint8_t(in & 255), uint8_t(in >> 8)});
  }
  w->write(b);
  w->close();
}

double segmentDistance(double px, double py, const std::array<double, 2>& a,
                       const std::array<double, 2>& b) {
  const double dx = b[0] - a[0], dy = b[1] - a[1];
  const double t =
      std::clamp(((px - a[0]) * dx + (py - a[1]) * dy) / (dx * dx + dy * dy), 0.0, 1.0);
  return std::hypot(a[0] + t * dx - px, a[1] + t * dy - py);
}

}  // namespace profile_test
using namespace profile_test;

TEST(Profile, HoldsExactlyThePointsWithinHalfTheWidthWithTheirDistances) {
  TempDir tmp;
  writeWall(tmp.file("wall.las"));
  nestlight::test::buildOctreeFrom(tmp.file("wall.las"), tmp.path() / "o", 3000);
  auto source = openReader(tmp.file("wall.las"));

  // Across the wall, then turning along the crossing wall; the faces half a millimetre off the
  // grid so that no point lies on them.
  const std::vector<std::array<double, 2>> line = {{kEast + 0.0005, kNorth + 10.0005},
                                                   {kEast + 15.0005, kNorth + 10.0005},
                                                   {kEast + 15.0005, kNorth + 30.0005}};
  ProfileOptions o;
  o.line = line;
  o.width = 0.25;
  o.outputs = {tmp.path() / "s.las", tmp.path() / "s.png", tmp.path() / "s.svg"};
  o.imageWidth = 300;
  const ProfileReport r = profileOctree(tmp.path() / "o", o);
  EXPECT_DOUBLE_EQ(r.length, 35);

  // The brute force: every source point within 0.125 of either segment.
  std::vector<std::array<int64_t, 3>> expected, got;
  PointBatch b;
  while (source->read(b, 65536))
    for (size_t i = 0; i < b.size(); ++i) {
      const double x = b.xyz[3 * i], y = b.xyz[3 * i + 1];
      if (std::min(segmentDistance(x, y, line[0], line[1]),
                   segmentDistance(x, y, line[1], line[2])) <= 0.125)
        expected.push_back({std::llround((x - kEast) * 1000), std::llround((y - kNorth) * 1000),
                            std::llround(b.xyz[3 * i + 2] * 1000)});
    }
  std::sort(expected.begin(), expected.end());
  ASSERT_GT(expected.size(), 500u);
  EXPECT_EQ(r.points, expected.size());

  auto back = openReader(tmp.file("s.las"));
  const PointLayout& l = back->header().layout;
  const int d = l.find("distance");
  ASSERT_GE(d, 0);
  size_t checked = 0;
  while (back->read(b, 65536))
    for (size_t i = 0; i < b.size(); ++i) {
      const double x = b.xyz[3 * i] - kEast, y = b.xyz[3 * i + 1] - kNorth;
      got.push_back(
          {std::llround(x * 1000), std::llround(y * 1000), std::llround(b.xyz[3 * i + 2] * 1000)});
      double along;
      std::memcpy(&along, b.attrs.data() + i * l.stride() + l.offset(d), 8);
      // On the first leg the distance along is x; on the second, 15 plus y beyond 10.
      if (y < 10.2 && x < 14.8) {
        EXPECT_NEAR(along, x - 0.0005, 1e-6);
        ++checked;
      } else if (x > 14.8 && y > 10.2) {
        EXPECT_NEAR(along, 15 + (y - 10.0005), 1e-6);
        ++checked;
      }
    }
  std::sort(got.begin(), got.end());
  EXPECT_EQ(got, expected);
  EXPECT_GT(checked, expected.size() / 2);

  // The plots: a PNG of the asked width, an SVG that embeds it and says what it holds.
  int w = 0, h = 0;
  const std::string png = nestlight::test::readFile(tmp.file("s.png"));
  ASSERT_GT(png.size(), 24u);
  w = (uint8_t(png[16]) << 24) | (uint8_t(png[17]) << 16) | (uint8_t(png[18]) << 8) |
      uint8_t(png[19]);
  h = (uint8_t(png[20]) << 24) | (uint8_t(png[21]) << 16) | (uint8_t(png[22]) << 8) |
      uint8_t(png[23]);
  EXPECT_EQ(w, 300);
  EXPECT_EQ(h, r.imageHeight);
  // True scale: the points' heights over their distances along, each padded (2% and 1% a side).
  EXPECT_NEAR(double(h) / w, (r.zMax - r.zMin) * 1.04 / ((r.alongMax - r.alongMin) * 1.02), 0.01);
  EXPECT_NEAR(r.alongMin, 10 - 0.0005, 0.01);  // the thick wall's near face on the first leg
  EXPECT_NEAR(r.alongMax, 15 + 10.1 - 0.0005,
              0.01);  // the crossing wall's far face (random: within 1 cm)
  const std::string svg = nestlight::test::readFile(tmp.file("s.svg"));
  EXPECT_NE(svg.find("data:image/png;base64,"), std::string::npos);
  EXPECT_NE(svg.find(std::to_string(r.points) + " points within 0.125 m"), std::string::npos);
}

TEST(Profile, AnEmptyCorridorStillWritesItsFilesAndBadLinesAreNamed) {
  TempDir tmp;
  writeWall(tmp.file("wall.las"));
  nestlight::test::buildOctreeFrom(tmp.file("wall.las"), tmp.path() / "o", 20000);
  std::string out;
  const std::string o = (tmp.path() / "o").string();
  // A line far from the walls: no point, but valid files.
  ASSERT_EQ(
      nestlight::test::runCli("profile " + o + " --line 0,0,1,1 --width 1 -o " + tmp.file("e.las") +
                                  " -o " + tmp.file("e.svg") + " --progress quiet",
                              &out),
      0)
      << out;
  EXPECT_NE(out.find("profile: 0 points"), std::string::npos) << out;
  EXPECT_EQ(openReader(tmp.file("e.las"))->header().declaredPoints.value_or(1), 0u);
  EXPECT_NE(nestlight::test::readFile(tmp.file("e.svg")).find("no point within the corridor"),
            std::string::npos);
  EXPECT_NE(nestlight::test::runCli(
                "profile " + o + " --line 0,0,1,x --width 1 -o " + tmp.file("x.las"), &out),
            0);
  EXPECT_NE(out.find("--line: value 4: expected a number, got 'x'"), std::string::npos) << out;
  EXPECT_NE(nestlight::test::runCli(
                "profile " + o + " --line 3,3,3,3 --width 1 -o " + tmp.file("x.las"), &out),
            0);
  EXPECT_NE(out.find("--line: a corridor needs a line of at least 2 distinct points"),
            std::string::npos)
      << out;
  EXPECT_FALSE(fs::exists(tmp.file("x.las")));
}
