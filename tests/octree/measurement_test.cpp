// Measurements: analytic values, national-grid coordinates without cancellation, and view-state
// JSON whose errors name the field.
#include "nestlight/octree/measurement.h"

#include <gtest/gtest.h>

#include <cmath>

#include "nestlight/octree/error.h"
#include "nestlight/octree/json_field.h"

using namespace nestlight;

namespace {
const Vec3d kGrid{512345.678, 5401234.567, 102.5};
Vec3d at(double x, double y, double z) {
  return {kGrid.x + x, kGrid.y + y, kGrid.z + z};
}
}  // namespace

TEST(Measurement, DistanceHeightAndAngleAreAnalytic) {
  Measurement d{Measurement::Kind::Distance, "", {at(0, 0, 0), at(3, 0, 4)}};
  // The coordinates' own rounding at these eastings is ~1e-10 m.
  EXPECT_NEAR(d.measure().value, 5, 1e-9);
  EXPECT_NEAR(d.measure().horizontal, 3, 1e-9);
  EXPECT_NEAR(d.measure().vertical, 4, 1e-9);
  EXPECT_EQ(d.describe("m"), "distance 5 m (plan 3 m, height 4 m)");

  Measurement h{Measurement::Kind::Height, "", {at(0, 0, 2), at(1, 1, -1)}};
  EXPECT_NEAR(h.measure().value, -3, 1e-12);
  EXPECT_NEAR(h.measure().horizontal, std::sqrt(2.0), 1e-9);

  EXPECT_NEAR(angleDegrees(at(1, 0, 0), at(0, 0, 0), at(0, 0, 1)), 90, 1e-9);
  EXPECT_NEAR(angleDegrees(at(1, 0, 0), at(0, 0, 0), at(1, 1, 0)), 45, 1e-9);
  // Nearly straight: acos would lose this to rounding; atan2 keeps 1e-4 degrees.
  const double tiny = std::tan(1e-4 * M_PI / 180);
  EXPECT_NEAR(angleDegrees(at(-1, 0, 0), at(0, 0, 0), at(1, tiny, 0)), 180 - 1e-4, 1e-7);
  EXPECT_EQ(angleDegrees(at(0, 0, 0), at(0, 0, 0), at(1, 0, 0)), 0);  // a degenerate leg

  Measurement p{Measurement::Kind::Polyline, "", {at(0, 0, 0), at(3, 4, 0), at(3, 4, 12)}};
  EXPECT_NEAR(p.measure().value, 17, 1e-9);
  EXPECT_NEAR(p.measure().horizontal, 5, 1e-9);
}

TEST(Measurement, AreasInPlanAndIn3dWithoutCancellationAtNationalGridCoordinates) {
  // A 2 x 2 square tilted 60 degrees about x: 4 in 3D, 2 in plan.
  const double c = std::cos(M_PI / 3), s = std::sin(M_PI / 3);
  Measurement a{Measurement::Kind::Area,
                "",
                {at(0, 0, 0), at(2, 0, 0), at(2, 2 * c, 2 * s), at(0, 2 * c, 2 * s)}};
  EXPECT_NEAR(a.measure().value, 4, 1e-8);
  EXPECT_NEAR(a.measure().horizontal, 2, 1e-8);

  // A 1 cm square: relative to its first point the area is good to the coordinates' precision;
  // the shoelace on raw coordinates (x_i y_j products of 2.8e12) is not.
  const std::vector<Vec3d> sq = {at(0, 0, 0), at(0.01, 0, 0), at(0.01, 0.01, 0), at(0, 0.01, 0)};
  EXPECT_NEAR(planArea(sq), 1e-4, 1e-11);
  EXPECT_NEAR(area3d(sq), 1e-4, 1e-11);
  double naive = 0;
  for (size_t i = 0; i < sq.size(); ++i)
    naive += sq[i].x * sq[(i + 1) % 4].y - sq[(i + 1) % 4].x * sq[i].y;
  EXPECT_GT(std::abs(std::abs(naive) / 2 - 1e-4), 1e-7);  // why the relative form matters
}

TEST(Measurement, ViewStateJsonRoundTripsAndNamesItsErrors) {
  Measurement m{
      Measurement::Kind::Angle, "arch springing", {at(0, 0, 0), at(1, 0, 0), at(1, 1, 0)}};
  const nlohmann::json j = m.toJson();
  const Measurement back = Measurement::fromJson(JsonField(j, "measurements[0]", "view.json"));
  EXPECT_EQ(back.toJson(), j);
  EXPECT_EQ(back.name, "arch springing");
  EXPECT_NEAR(back.measure().value, 90, 1e-9);

  auto error = [](const nlohmann::json& v) -> std::string {
    try {
      Measurement::fromJson(JsonField(v, "measurements[2]", "view.json"));
    } catch (const Error& e) {
      return e.what();
    }
    return "(no error)";
  };
  EXPECT_EQ(error({{"type", "distance"}, {"points", {{0, 0, 0}}}}),
            "view.json: measurements[2].points: a distance needs 2 points, got 1");
  EXPECT_EQ(error({{"type", "area"}, {"points", {{0, 0, 0}, {1, 0, 0}}}}),
            "view.json: measurements[2].points: an area needs at least 3 points, got 2");
  EXPECT_EQ(error({{"type", "volume"}, {"points", nlohmann::json::array()}}),
            "view.json: measurements[2].type: 'volume' is not one of: distance, polyline, area, "
            "height, angle");
  EXPECT_NE(error({{"type", "height"}, {"points", {{0, 0, 0}, {1, 0, "x"}}}})
                .find("measurements[2].points[1]"),
            std::string::npos);
  EXPECT_THROW((Measurement{Measurement::Kind::Angle, "", {at(0, 0, 0)}}.measure()), Error);
}
