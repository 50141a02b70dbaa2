// Clipping volumes: exact membership (boundaries, national-grid coordinates), node culling that
// never culls a kept point nor keeps a clipped one, and files whose errors name the field.
#include "nestlight/octree/clip_volume.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "nestlight/octree/error.h"
#include "test_support.h"

using namespace nestlight;

namespace {

ClipSet parse(const std::string& text) {
  return ClipSet::fromJson(nlohmann::json::parse(text), "clip.json");
}

std::string errorText(const std::string& text) {
  try {
    parse(text);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(ClipVolume, BoxKeepsItsBoundaryAndTurnsWithItsRotation) {
  const ClipVolume b = ClipVolume::box({1, 2, 3}, {2, 4, 6});
  EXPECT_TRUE(b.contains({0, 0, 0}));  // a corner: boundaries are kept
  EXPECT_TRUE(b.contains({2, 4, 6}));
  EXPECT_FALSE(b.contains({2.000001, 2, 3}));
  EXPECT_FALSE(b.contains({1, 2, NAN}));  // NaN is never inside

  // 45 degrees about z: the box's x axis runs along (1, 1)/sqrt(2).
  const ClipVolume r = ClipVolume::box({0, 0, 0}, {4, 1, 1}, {0, 0, 45});
  EXPECT_TRUE(r.contains({1.4, 1.4, 0}));     // 1.98 along its x (half size 2)
  EXPECT_FALSE(r.contains({1.5, 1.5, 0}));    // 2.12 along it
  EXPECT_FALSE(r.contains({1.4, 0, 0}));      // 0.99 across it (half size 0.5)
  EXPECT_TRUE(r.contains({0.3, -0.3, 0.5}));  // 0.42 across, on the top face
}

TEST(ClipVolume, NationalGridCoordinatesClipToTheMillimetre) {
  // A 2 mm box around a point at six-digit eastings: a float32 frame would move these by 6 cm.
  const ClipVolume b = ClipVolume::box({512345.678, 5401234.567, 102.345}, {0.002, 0.002, 0.002});
  EXPECT_TRUE(b.contains({512345.678, 5401234.567, 102.345}));
  EXPECT_TRUE(b.contains({512345.6789, 5401234.5679, 102.3459}));
  EXPECT_FALSE(b.contains({512345.6791, 5401234.567, 102.345}));
  EXPECT_FALSE(b.contains({512345.678, 5401234.5659, 102.345}));
}

TEST(ClipVolume, AdjacentPolygonsShareTheirEdgeWithoutDoubleCounting) {
  const ClipVolume left = ClipVolume::polygon({{0, 0}, {1, 0}, {1, 1}, {0, 1}});
  const ClipVolume right = ClipVolume::polygon({{1, 0}, {2, 0}, {2, 1}, {1, 1}});
  // Points on the shared edge x = 1 and on the shared corners' rows: each in exactly one.
  for (double y : {0.0, 0.25, 0.5, 0.999}) {
    const Vec3d p{1, y, 0};
    EXPECT_EQ(int(left.contains(p)) + int(right.contains(p)), 1) << "y " << y;
  }
  // A concave polygon (an L): its notch is outside.
  const ClipVolume l = ClipVolume::polygon({{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}});
  EXPECT_TRUE(l.contains({0.5, 1.5, 0}));
  EXPECT_TRUE(l.contains({1.5, 0.5, 0}));
  EXPECT_FALSE(l.contains({1.5, 1.5, 0}));
  // Its z range.
  const ClipVolume lz = ClipVolume::polygon(l.points, 10, 20);
  EXPECT_FALSE(lz.contains({0.5, 0.5, 9.99}));
  EXPECT_TRUE(lz.contains({0.5, 0.5, 20}));
}

TEST(ClipVolume, CorridorHoldsWhatLiesWithinHalfItsWidthAndMeasuresAlongIt) {
  const ClipVolume c = ClipVolume::corridor({{0, 0}, {10, 0}, {10, 10}}, 2);
  EXPECT_DOUBLE_EQ(c.length(), 20);
  EXPECT_TRUE(c.contains({5, 1, 100}));  // the width is in plan: any height
  EXPECT_FALSE(c.contains({5, 1.001, 0}));
  EXPECT_TRUE(c.contains({11, 5, 0}));
  EXPECT_TRUE(c.contains({-0.6, 0.6, 0}));  // the rounded end: 0.85 from the first vertex
  EXPECT_FALSE(c.contains({-0.8, 0.8, 0}));
  EXPECT_DOUBLE_EQ(c.along({5, 0.5, 0}), 5);
  EXPECT_DOUBLE_EQ(c.along({10.5, 4, 0}), 14);
  EXPECT_DOUBLE_EQ(c.along({-0.5, 0, 0}), -0.5);   // before the first vertex
  EXPECT_DOUBLE_EQ(c.along({10, 10.5, 0}), 20.5);  // past the last
}

// The culling contract behind `export --clip`: None means no point of the box is kept and All
// that every one is, for any volume and box; Partial is the only answer allowed to be unsure.
TEST(ClipVolume, NodeCullingNeverDisagreesWithThePointTest) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  const Vec3d o{500000, 5000000, 100};  // national grid: rounding there must not flip answers
  std::vector<ClipSet> sets;
  {
    ClipSet s;
    s.volumes.push_back(ClipVolume::box({o.x + 5, o.y + 5, o.z + 5}, {4, 3, 2}, {10, 20, 30}));
    sets.push_back(s);
    s.volumes.push_back(ClipVolume::polygon({{o.x + 1, o.y + 1},
                                             {o.x + 9, o.y + 2},
                                             {o.x + 5, o.y + 5},
                                             {o.x + 8, o.y + 9},
                                             {o.x + 2, o.y + 8}},
                                            o.z + 2, o.z + 8));
    s.volumes.back().mode = ClipVolume::Mode::Outside;
    sets.push_back(s);
    ClipSet c;
    c.volumes.push_back(
        ClipVolume::corridor({{o.x + 1, o.y + 1}, {o.x + 9, o.y + 4}, {o.x + 3, o.y + 9}}, 1.5));
    sets.push_back(c);
    c.volumes.back().mode = ClipVolume::Mode::Outside;
    sets.push_back(c);
  }
  int decided[3] = {0, 0, 0};
  for (const ClipSet& set : sets)
    for (int trial = 0; trial < 3000; ++trial) {
      // Boxes of every size from a node at depth 6 to the whole region, some on exact edges.
      const double size = std::pow(2.0, -int(u(rng) * 6)) * 10;
      Box3d box;
      box.min = {o.x + std::floor(u(rng) * 10 / size) * size,
                 o.y + std::floor(u(rng) * 10 / size) * size,
                 o.z + std::floor(u(rng) * 10 / size) * size};
      box.max = {box.min.x + size, box.min.y + size, box.min.z + size};
      const Overlap ov = set.keeps(box);
      ++decided[int(ov)];
      if (ov == Overlap::Partial) continue;
      for (int k = 0; k < 200; ++k) {
        Vec3d p{box.min.x + u(rng) * size, box.min.y + u(rng) * size, box.min.z + u(rng) * size};
        if (k < 8)  // the corners
          p = {(k & 1) ? box.max.x : box.min.x, (k & 2) ? box.max.y : box.min.y,
               (k & 4) ? box.max.z : box.min.z};
        ASSERT_EQ(set.keeps(p), ov == Overlap::All)
            << "trial " << trial << " box at " << box.min.x - o.x << "," << box.min.y - o.y << ","
            << box.min.z - o.z << " size " << size;
      }
    }
  // The test means something only if the cheap tests decide often.
  EXPECT_GT(decided[int(Overlap::None)], 1000);
  EXPECT_GT(decided[int(Overlap::All)], 100);
}

TEST(ClipVolume, FilesRoundTripAndErrorsNameTheField) {
  const ClipSet s = parse(R"({"clipping": [
      {"type": "box", "center": [1, 2, 3], "size": [2, 2, 2], "rotation": [0, 0, 30]},
      {"type": "polygon", "points": [[0, 0], [4, 0], [4, 4], [0, 4], [0, 0]], "z": [-1, 1],
       "mode": "outside"},
      {"type": "corridor", "points": [[0, 0], [5, 5]], "width": 0.5}]})");
  ASSERT_EQ(s.volumes.size(), 3u);
  EXPECT_EQ(s.volumes[1].points.size(), 4u);  // the closing vertex is the first one again
  const ClipSet back =
      ClipSet::fromJson(nlohmann::json{{"clipping", s.toJson()}}, "round-trip.json");
  EXPECT_EQ(back.toJson(), s.toJson());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-2, 6);
  for (int i = 0; i < 2000; ++i) {
    const Vec3d p{u(rng), u(rng), u(rng)};
    ASSERT_EQ(back.keeps(p), s.keeps(p));
  }
  // One volume alone is a file too.
  EXPECT_EQ(parse(R"({"type": "box", "center": [0, 0, 0], "size": [1, 1, 1]})").volumes.size(), 1u);

  EXPECT_EQ(errorText(R"({"clipping": [{"type": "polygon",
      "points": [[0, 0], [2, 2], [2, 0], [0, 2]]}]})"),
            "clip.json: clipping[0].points: the polygon crosses itself: edges 0-1 and 2-3 meet");
  EXPECT_EQ(errorText(R"({"clipping": [{"type": "polygon",
      "points": [[0, 0], [2, 0], [1, 0], [1, 1]]}]})"),
            "clip.json: clipping[0].points: the polygon crosses itself: edges 0-1 and 1-2 fold "
            "back along each other");
  EXPECT_EQ(errorText(R"({"clipping": [{"type": "polygon", "points": [[0, 0], [1, 1]]}]})"),
            "clip.json: clipping[0].points: expected at least 3 points, got 2");
  EXPECT_EQ(
      errorText(R"({"clipping": [{"type": "box", "center": [0, 0, 0], "size": [1, -1, 1]}]})"),
      "clip.json: clipping[0].size[1]: expected a number in [0, inf], got -1");
  EXPECT_EQ(errorText(R"({"clipping": [{"type": "sphere"}]})"),
            "clip.json: clipping[0].type: 'sphere' is not one of: box, polygon, corridor");
  EXPECT_EQ(
      errorText(R"({"clipping": [{"type": "corridor", "points": [[0, 0], [1, 1]], "width": 0}]})"),
      "clip.json: clipping[0].width: expected a positive width");
  EXPECT_EQ(errorText(R"({"clipping": [{"type": "box", "center": [0, 0, 0], "size": [1, 1, 1],
      "colour": 1}]})")
                .rfind("clip.json: clipping[0].colour: unknown field", 0),
            0u);
  EXPECT_EQ(errorText(R"({"volumes": []})"), "clip.json: missing \"clipping\"");
}
