// View states: every field round-trips through the file, partial states keep defaults, errors
// name the field, and a state from elsewhere warns.
#include "nestlight/frame/view_state.h"

#include <gtest/gtest.h>

#include "nestlight/octree/error.h"
#include "test_support.h"

using namespace nestlight;
using namespace nestlight::frame;

namespace view_state_test {

std::string errorOf(const std::string& text) {
  try {
    ViewState::fromJson(nlohmann::json::parse(text), "view.json");
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace view_state_test
using namespace view_state_test;

TEST(ViewState, EveryFieldRoundTripsThroughTheFile) {
  ViewState s;
  s.octree = "nave.octree";
  Box3d b;
  b.min = {512000, 5401000, 90}, b.max = {512100, 5401050, 130};
  s.octreeBounds = b;
  s.crs = "\"OSGB 1936 / British National Grid\" (EPSG:27700), unit metre, from WKT";
  Camera c;
  c.eye = {512010.125, 5401020.5, 101.75};
  c.target = {512050, 5401025, 110};
  c.fovYDegrees = 45;
  s.camera = c;
  s.colour = ColourMode::Intensity;
  s.budgets.points = 12'000'000;
  s.budgets.spacingPixels = 0.75;
  s.settings.rasteriser = Rasteriser::Compute;
  s.settings.splatting = Splatting::Basic;
  s.settings.edlStrength = 0.5f;
  s.clipping.volumes.push_back(ClipVolume::box({512050, 5401025, 110}, {20, 10, 30}, {0, 0, 15}));
  s.clipping.volumes.push_back(
      ClipVolume::polygon({{512000, 5401000}, {512010, 5401000}, {512010, 5401010}}));
  s.clipping.volumes.back().mode = ClipVolume::Mode::Outside;
  s.measurements.push_back({Measurement::Kind::Distance,
                            "nave width",
                            {{512001, 5401001, 100}, {512031, 5401001, 100}}});
  s.annotations.push_back({{512040.5, 5401030.25, 104}, "crack", "first seen 2024; 2 mm wide"});
  s.gi = {{"method", "pbgi"}, {"parameters", {{"quality", 2}}}};

  nestlight::test::TempDir tmp;
  s.save(tmp.path() / "view.json");
  const ViewState back = ViewState::load(tmp.path() / "view.json");
  EXPECT_EQ(back.toJson(), s.toJson());
  ASSERT_TRUE(back.camera);
  EXPECT_EQ(back.camera->eye, c.eye);  // national-grid coordinates, exactly
  EXPECT_EQ(back.colour, ColourMode::Intensity);
  EXPECT_EQ(back.settings.rasteriser, Rasteriser::Compute);
  EXPECT_EQ(back.budgets.points, 12'000'000u);
  ASSERT_EQ(back.measurements.size(), 1u);
  EXPECT_EQ(back.measurements[0].measure().value, 30);
  ASSERT_EQ(back.annotations.size(), 1u);
  EXPECT_EQ(back.annotations[0].text, "first seen 2024; 2 mm wide");
  EXPECT_EQ(back.gi["method"], "pbgi");
  EXPECT_FALSE(std::filesystem::exists(tmp.path() / "view.json.tmp"));
  // The clipping array is the one export --clip reads.
  EXPECT_EQ(ClipSet::load(tmp.path() / "view.json").toJson(), s.clipping.toJson());
}

TEST(ViewState, PartialStatesKeepTheDefaultsAndErrorsNameTheField) {
  const ViewState cam = ViewState::fromJson(
      nlohmann::json::parse(R"({"camera": {"eye": [0, 0, 10], "target": [0, 5, 0]}})"), "v.json");
  ASSERT_TRUE(cam.camera);
  EXPECT_FALSE(cam.colour);
  EXPECT_EQ(cam.budgets.points, streaming::Budgets{}.points);
  EXPECT_TRUE(cam.clipping.empty());

  EXPECT_EQ(errorOf(R"({"camera": {"eye": [0, 0, "x"], "target": [0, 0, 0]}})"),
            "view.json: camera.eye[2]: expected a number, got string");
  EXPECT_EQ(errorOf(R"({"camera": {"eye": [1, 2, 3], "target": [1, 2, 3]}})"),
            "view.json: camera.target: the target is the eye: no direction to look");
  EXPECT_EQ(errorOf(R"({"version": 2})"),
            "view.json: version: version 2 was written by a newer nestlight (this one reads 1)");
  EXPECT_EQ(errorOf(R"({"colour": {"mode": "rainbow"}})")
                .rfind("view.json: colour.mode: unknown colour mode 'rainbow'", 0),
            0u);
  EXPECT_EQ(
      errorOf(R"({"clipping": [{"type": "polygon", "points": [[0, 0], [2, 2], [2, 0], [0, 2]]}]})"),
      "view.json: clipping[0].points: the polygon crosses itself: edges 0-1 and 2-3 meet");
  EXPECT_EQ(errorOf(R"({"measurements": [{"type": "angle", "points": [[0, 0, 0]]}]})"),
            "view.json: measurements[0].points: an angle needs 3 points, got 1");
  EXPECT_EQ(errorOf(R"({"annotations": [{"position": [0, 0, 0], "title": ""}]})"),
            "view.json: annotations[0].title: expected a title (the label shown at the point)");
  EXPECT_EQ(errorOf(R"({"splatting": {"edl_radius": 9}})"),
            "view.json: splatting.edl_radius: expected a number in [0, 6], got 9");
  EXPECT_EQ(errorOf(R"({"camra": {}})").rfind("view.json: camra: unknown field", 0), 0u);
}

TEST(ViewState, AStateFromAnotherOctreeWarns) {
  ViewState s;
  Box3d saved;
  saved.min = {0, 0, 0}, saved.max = {10, 10, 10};
  s.octreeBounds = saved;
  s.octree = "chapel.octree";
  Box3d overlapping;
  overlapping.min = {9, 9, 9}, overlapping.max = {20, 20, 20};
  EXPECT_EQ(s.boundsWarning(overlapping), "");
  Box3d elsewhere;
  elsewhere.min = {512000, 5401000, 0}, elsewhere.max = {512100, 5401100, 50};
  const std::string w = s.boundsWarning(elsewhere);
  EXPECT_NE(w.find("saved from chapel.octree"), std::string::npos) << w;
  EXPECT_NE(w.find("do not overlap"), std::string::npos) << w;
  EXPECT_EQ(ViewState{}.boundsWarning(elsewhere), "");  // a state that does not say
}
