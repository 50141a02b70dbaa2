// `export --clip` and `info --clip` write and count exactly the points a brute-force filter of
// every point keeps (multiset equality of integer positions), from every level, on generated
// scans in national-grid coordinates and on the shared autzen scan. The filters here are the
// test's own geometry, not the library's.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "nestlight/converters/builder.h"
#include "nestlight/converters/export.h"
#include "nestlight/converters/reader.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/octree/octree_reader.h"
#include "test_support.h"

using namespace nestlight;
using nestlight::test::TempDir;
namespace fs = std::filesystem;

namespace clip_export_test {

using Cell = std::array<int64_t, 3>;
using Filter = std::function<bool(double, double, double)>;

// The points of a point file as integers in a quantisation (the octree's or a LAS file's).
std::vector<Cell> cellsOf(PointReader& r, const Vec3d& offset, const Vec3d& scale,
                          const Filter& keep = {}) {
  std::vector<Cell> out;
  PointBatch b;
  r.rewind();
  while (r.read(b, 65536))
    for (size_t i = 0; i < b.size(); ++i) {
      const double* p = &b.xyz[3 * i];
      if (keep && !keep(p[0], p[1], p[2])) continue;
      out.push_back({std::llround((p[0] - offset.x) / scale.x),
                     std::llround((p[1] - offset.y) / scale.y),
                     std::llround((p[2] - offset.z) / scale.z)});
    }
  std::sort(out.begin(), out.end());
  return out;
}

// Every stored point of the octree, in its grid, that `keep` keeps (world coordinates).
std::vector<Cell> bruteForce(const fs::path& dir, const Filter& keep) {
  OctreeReader r(dir);
  const Metadata& m = r.metadata();
  std::vector<Cell> out;
  for (const auto& [key, e] : r.allNodes()) {
    const PointBuffer p = r.readNode(key);
    for (size_t i = 0; i < p.size(); ++i) {
      const Cell c{p.pos[3 * i], p.pos[3 * i + 1], p.pos[3 * i + 2]};
      if (keep(m.offset.x + c[0] * m.scale.x, m.offset.y + c[1] * m.scale.y,
               m.offset.z + c[2] * m.scale.z))
        out.push_back(c);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

double segmentDistance(double px, double py, double ax, double ay, double bx, double by) {
  const double dx = bx - ax, dy = by - ay;
  const double t = std::clamp(((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy), 0.0, 1.0);
  return std::hypot(ax + t * dx - px, ay + t * dy - py);
}

struct Case {
  std::string name;
  ClipSet clip;
  Filter keep;
};

// Volumes about `o` (national grid), their faces half a millimetre off the 1 mm grid so that no
// point sits on one (the test's geometry and the library's may round differently there).
std::vector<Case> cases(const Vec3d& o) {
  std::vector<Case> out;
  const double h = 0.0005;
  {
    Case c{"box", {}, {}};
    c.clip.volumes.push_back(
        ClipVolume::box({o.x + 30 + h, o.y + 40 + h, o.z + 20 + h}, {40, 30, 50}));
    c.keep = [=](double x, double y, double z) {
      return std::abs(x - (o.x + 30 + h)) <= 20 && std::abs(y - (o.y + 40 + h)) <= 15 &&
             std::abs(z - (o.z + 20 + h)) <= 25;
    };
    out.push_back(c);
  }
  {
    Case c{"rotated box, outside", {}, {}};
    c.clip.volumes.push_back(
        ClipVolume::box({o.x + 50, o.y + 50, o.z + 50}, {60, 20, 80}, {0, 0, 30}));
    c.clip.volumes.back().mode = ClipVolume::Mode::Outside;
    const double cs = std::cos(M_PI / 6), sn = std::sin(M_PI / 6);
    c.keep = [=](double x, double y, double z) {
      const double dx = x - (o.x + 50), dy = y - (o.y + 50);
      const double u = cs * dx + sn * dy, v = -sn * dx + cs * dy;
      return !(std::abs(u) <= 30 && std::abs(v) <= 10 && std::abs(z - (o.z + 50)) <= 40);
    };
    out.push_back(c);
  }
  {
    // An L: the union of two rectangles, between two heights.
    Case c{"concave polygon with a z range", {}, {}};
    const double a = 10 + h, b = 70 + h, m = 40 + h;
    c.clip.volumes.push_back(ClipVolume::polygon({{o.x + a, o.y + a},
                                                  {o.x + b, o.y + a},
                                                  {o.x + b, o.y + m},
                                                  {o.x + m, o.y + m},
                                                  {o.x + m, o.y + b},
                                                  {o.x + a, o.y + b}},
                                                 o.z + 5 + h, o.z + 60 + h));
    c.keep = [=](double x, double y, double z) {
      const double X = x - o.x, Y = y - o.y, Z = z - o.z;
      if (Z < 5 + h || Z > 60 + h) return false;
      return (X >= a && X <= b && Y >= a && Y <= m) || (X >= a && X <= m && Y >= a && Y <= b);
    };
    out.push_back(c);
  }
  {
    Case c{"corridor", {}, {}};
    c.clip.volumes.push_back(ClipVolume::corridor(
        {{o.x + 5 + h, o.y + 10 + h}, {o.x + 60 + h, o.y + 30 + h}, {o.x + 80 + h, o.y + 90 + h}},
        6));
    c.keep = [=](double x, double y, double) {
      return std::min(segmentDistance(x, y, o.x + 5 + h, o.y + 10 + h, o.x + 60 + h, o.y + 30 + h),
                      segmentDistance(x, y, o.x + 60 + h, o.y + 30 + h, o.x + 80 + h,
                                      o.y + 90 + h)) <= 3;
    };
    out.push_back(c);
  }
  {
    Case c{"box inside, minus a box", {}, {}};
    c.clip.volumes.push_back(
        ClipVolume::box({o.x + 50 + h, o.y + 50 + h, o.z + 50 + h}, {80, 80, 80}));
    c.clip.volumes.push_back(
        ClipVolume::box({o.x + 50 + h, o.y + 50 + h, o.z + 50 + h}, {20, 200, 200}));
    c.clip.volumes.back().mode = ClipVolume::Mode::Outside;
    c.keep = [=](double x, double y, double z) {
      const double X = x - (o.x + 50 + h), Y = y - (o.y + 50 + h), Z = z - (o.z + 50 + h);
      return std::abs(X) <= 40 && std::abs(Y) <= 40 && std::abs(Z) <= 40 && std::abs(X) > 10;
    };
    out.push_back(c);
  }
  {
    Case c{"a box that holds no point", {}, {}};
    c.clip.volumes.push_back(ClipVolume::box({o.x - 500, o.y, o.z}, {10, 10, 10}));
    c.keep = [](double, double, double) { return false; };
    out.push_back(c);
  }
  {
    Case c{"a box that holds every point", {}, {}};
    c.clip.volumes.push_back(ClipVolume::box({o.x + 50, o.y + 50, o.z + 50}, {1000, 1000, 1000}));
    c.keep = [](double, double, double) { return true; };
    out.push_back(c);
  }
  return out;
}

}  // namespace clip_export_test
using namespace clip_export_test;

TEST(ClipExport, ExportAndCountEqualABruteForceFilterOnNationalGridScans) {
  TempDir tmp;
  const Vec3d o{512000, 5401000, 100};
  for (const SyntheticShape shape : {SyntheticShape::Surfaces, SyntheticShape::Cube}) {
    SyntheticSpec spec;
    spec.shape = shape;
    spec.points = 60000;
    spec.origin = o;
    spec.seed = 11;
    BuildOptions bo;
    bo.output = tmp.path() / syntheticShapeName(shape);
    bo.progress = ProgressMode::Quiet;
    bo.threads = 2;
    bo.maxNodePoints = 2000;  // several levels: the clip must reach into every one
    std::vector<std::unique_ptr<PointReader>> readers;
    readers.push_back(openSynthetic(spec));
    const BuildReport built = buildOctree(std::move(readers), bo);
    ASSERT_GE(built.metadata.depth, 2u);
    const Metadata& m = built.metadata;
    for (const Case& c : cases(o)) {
      SCOPED_TRACE(std::string(syntheticShapeName(shape)) + ": " + c.name);
      const std::vector<Cell> expected = bruteForce(bo.output, c.keep);
      ExportOptions eo;
      eo.clip = &c.clip;
      eo.threads = 2;
      const fs::path las = tmp.path() / "clipped.las";
      const ExportReport written = exportOctree(bo.output, las, eo);
      EXPECT_EQ(written.points, expected.size());
      auto back = openReader(las.string());
      EXPECT_EQ(cellsOf(*back, m.offset, m.scale), expected);
      const ExportReport counted = countOctree(bo.output, eo);
      EXPECT_EQ(counted.points, expected.size());
      if (c.name.rfind("a box that holds", 0) == 0) {
        // Decided from the hierarchy alone: nothing tested point by point.
        EXPECT_EQ(counted.pointsTested, 0u);
      } else if (shape == SyntheticShape::Cube) {
        // A filled cube: the volumes must cull whole nodes or keep them whole.
        EXPECT_GT(written.nodesSkipped + written.nodesWhole, 0u);
      }
    }
  }
}

TEST(ClipExport, AutzenBoxEqualsAFilterOfTheSourceFile) {
  NL_REQUIRE_SHARED("scans/autzen_trim.las");
  const fs::path src = nestlight::test::sharedData() / "scans/autzen_trim.las";
  TempDir tmp;
  nestlight::test::buildOctreeFrom(src, tmp.path() / "o", 5000);
  auto source = openReader(src.string());
  ASSERT_TRUE(source->header().scale && source->header().offset);
  const Vec3d scale = *source->header().scale, offset = *source->header().offset;
  OctreeReader reader(tmp.path() / "o");
  const Box3d b = reader.metadata().bounds;
  // The middle third in plan, every height; faces half a quantum off the source's grid.
  const double hx = scale.x / 2, hy = scale.y / 2;
  const double x0 = std::round((b.min.x + (b.max.x - b.min.x) / 3) / scale.x) * scale.x + hx;
  const double x1 = std::round((b.min.x + 2 * (b.max.x - b.min.x) / 3) / scale.x) * scale.x + hx;
  const double y0 = std::round((b.min.y + (b.max.y - b.min.y) / 4) / scale.y) * scale.y + hy;
  const double y1 = std::round((b.min.y + 3 * (b.max.y - b.min.y) / 4) / scale.y) * scale.y + hy;
  ClipSet clip;
  clip.volumes.push_back(ClipVolume::box({(x0 + x1) / 2, (y0 + y1) / 2, (b.min.z + b.max.z) / 2},
                                         {x1 - x0, y1 - y0, 2 * (b.max.z - b.min.z) + 2}));
  const std::vector<Cell> expected =
      cellsOf(*source, offset, scale,
              [&](double x, double y, double) { return x >= x0 && x <= x1 && y >= y0 && y <= y1; });
  ASSERT_GT(expected.size(), 1000u);
  ExportOptions eo;
  eo.clip = &clip;
  const fs::path out = tmp.path() / "clipped.las";
  EXPECT_EQ(exportOctree(tmp.path() / "o", out, eo).points, expected.size());
  auto back = openReader(out.string());
  EXPECT_EQ(cellsOf(*back, offset, scale), expected);
  EXPECT_EQ(countOctree(tmp.path() / "o", eo).points, expected.size());
}

TEST(ClipExport, TheCommandLineCountsExportsAndNamesBadFiles) {
  TempDir tmp;
  SyntheticSpec spec;
  spec.points = 20000;
  writeSynthetic(spec, tmp.file("scan.las"));
  nestlight::test::buildOctreeFrom(tmp.file("scan.las"), tmp.path() / "o", 3000);
  nestlight::test::writeFile(tmp.file("box.json"),
                             R"({"clipping": [{"type": "box", "center": [50.0005, 50.0005, 50.0005],
                                 "size": [50, 50, 50]}]})");
  std::string out;
  ASSERT_EQ(nestlight::test::runCli(
                "info " + (tmp.path() / "o").string() + " --clip " + tmp.file("box.json"), &out),
            0)
      << out;
  const size_t at = out.find("clip       ");
  ASSERT_NE(at, std::string::npos) << out;
  const uint64_t counted = std::stoull(out.substr(out.find(": ", at) + 2));
  ASSERT_EQ(
      nestlight::test::runCli("export " + (tmp.path() / "o").string() + " -o " + tmp.file("c.laz") +
                                  " --clip " + tmp.file("box.json") + " --progress quiet",
                              &out),
      0)
      << out;
  EXPECT_NE(out.find("wrote " + std::to_string(counted) + " points"), std::string::npos) << out;
  EXPECT_GT(counted, 0u);
  EXPECT_LT(counted, 20000u);

  nestlight::test::writeFile(tmp.file("bad.json"),
                             R"({"clipping": [{"type": "polygon",
                                 "points": [[0, 0], [9, 9], [9, 0], [0, 9]]}]})");
  EXPECT_NE(nestlight::test::runCli("export " + (tmp.path() / "o").string() + " -o " +
                                        tmp.file("x.las") + " --clip " + tmp.file("bad.json"),
                                    &out),
            0);
  EXPECT_NE(out.find("bad.json: clipping[0].points: the polygon crosses itself"), std::string::npos)
      << out;
  EXPECT_FALSE(fs::exists(tmp.file("x.las")));
}
