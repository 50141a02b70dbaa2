// Scene files: what parses, and that every mistake names its field.
#include "nestlight/gi/scene.h"

#include <gtest/gtest.h>

#include "test_support.h"

using namespace nestlight;
using namespace nestlight::gi;
using json = nlohmann::json;

namespace {

json minimal() {
  return json::parse(R"({
    "version": 1,
    "meshes": [{"path": "bunny.ply"}],
    "camera": {"eye": [0, -5, 1], "target": [0, 0, 0.5]}
  })");
}

// The error's position (the JSON path of the field) when parsing fails.
std::string errorField(const json& j) {
  try {
    parseScene(j, "/scenes/test.json");
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), "/scenes/test.json");
    return e.position();
  }
  ADD_FAILURE() << "no error for " << j.dump();
  return "";
}

}  // namespace

TEST(Scene, FullSceneParses) {
  json j = json::parse(R"({
    "version": 1,
    "origin": [500000, 5000000, 100],
    "octrees": ["scan.octree", {"path": "/abs/other.octree", "max_level": 5, "memory_budget": "512MiB",
                                 "radius_scale": 1.5, "colour_scale": 2}],
    "materials": {"gold": {"type": "ggx", "base_color": [1, 0.8, 0.3], "roughness": 0.2, "metallic": 1},
                  "paint": {"type": "principled", "base_color": 0.5, "clearcoat": 1, "sheen": 0.2}},
    "meshes": [{"path": "meshes/bunny.ply", "material": "gold",
                "transform": {"translate": [1, 2, 3], "rotate": [0, 0, 90], "scale": 2},
                "surfels": {"method": "poisson", "count": 5000}},
               {"path": "x.obj", "material": {"type": "lambert", "base_color": [0.2, 0.3, 0.4]}}],
    "lights": [{"type": "point", "position": [0, 0, 10], "intensity": 100},
               {"type": "spot", "position": [0, 0, 10], "direction": [0, 0, -1], "intensity": [1, 2, 3],
                "inner_angle": 10, "outer_angle": 20},
               {"type": "directional", "direction": [0, 0, -2], "irradiance": 3}],
    "environment": {"path": "sky.hdr", "rotation": 90, "scale": 0.5},
    "camera": {"eye": [0, -5, 1], "target": [0, 0, 0.5], "fov": 40, "width": 64, "height": 32},
    "camera_path": {"fps": 24, "keyframes": [{"time": 0, "eye": [0, -5, 1], "target": [0, 0, 0]},
                                              {"time": 2, "eye": [5, 0, 1], "target": [0, 0, 0]}]},
    "gi": {"method": "direct", "mode": "albedo", "max_bounces": 2, "samples_per_pixel": 64,
           "target_relative_error": 0.01, "time_limit": 30, "seed": 7, "parameters": {"x": 1}},
    "output": {"exr": "out/a.exr", "png": "out/a.png", "exposure": -1}
  })");
  Scene s = parseScene(j, "/scenes/test.json");
  EXPECT_TRUE(s.originSet);
  EXPECT_EQ(s.origin, glm::dvec3(500000, 5000000, 100));
  ASSERT_EQ(s.octrees.size(), 2u);
  EXPECT_EQ(s.octrees[0].path, "/scenes/scan.octree");  // relative to the scene file
  EXPECT_EQ(s.octrees[1].path, "/abs/other.octree");
  EXPECT_EQ(*s.octrees[1].maxLevel, 5);
  EXPECT_EQ(s.octrees[1].memoryBudget, 512ull << 20);
  ASSERT_EQ(s.materials.size(), 3u);  // two named, one inline
  ASSERT_EQ(s.meshes.size(), 2u);
  EXPECT_EQ(s.materials[s.meshes[0].material].name, "gold");
  EXPECT_EQ(s.materials[s.meshes[0].material].type, MaterialType::GGX);
  EXPECT_EQ(s.materials[s.meshes[1].material].baseColor, Rgb(0.2f, 0.3f, 0.4f));
  EXPECT_EQ(s.meshes[0].surfelMethod, SurfelSampling::PoissonDisk);
  EXPECT_EQ(s.meshes[0].surfelCount, 5000u);
  // translate * rotate(z, 90) * scale(2): object +x goes to world +y, doubled, then moved.
  glm::dvec4 p = s.meshes[0].worldFromObject * glm::dvec4(1, 0, 0, 1);
  EXPECT_NEAR(p.x, 1, 1e-12);
  EXPECT_NEAR(p.y, 4, 1e-12);
  EXPECT_NEAR(p.z, 3, 1e-12);
  ASSERT_EQ(s.lights.size(), 3u);
  EXPECT_EQ(s.lights[1].type, LightType::Spot);
  EXPECT_NEAR(s.lights[2].direction.z, -1.0f, 1e-7);  // normalised
  EXPECT_EQ(s.environment->path, "/scenes/sky.hdr");
  EXPECT_EQ(s.camera.width, 64);
  EXPECT_EQ(s.cameraPath.keys.size(), 2u);
  EXPECT_EQ(s.cameraPath.fps, 24);
  EXPECT_EQ(s.gi.method, "direct");
  EXPECT_EQ(s.gi.mode, RadianceMode::Albedo);
  EXPECT_EQ(s.output.exr, "/scenes/out/a.exr");
  // Local coordinates subtract the origin in double: a national-grid point keeps its millimetres.
  glm::vec3 l = s.local(glm::dvec3(500000.001, 5000000.002, 100.003));
  EXPECT_NEAR(l.x, 0.001f, 1e-6);
  EXPECT_NEAR(l.y, 0.002f, 1e-6);
}

// Differential rendering tells inserted objects from meshes of the captured scene (a lamp that
// was there when the scan was made); a mesh that says nothing is an inserted object.
TEST(Scene, MeshesAreInsertedUnlessMarkedCaptured) {
  json j = minimal();
  j["meshes"].push_back(json{{"path", "panel.obj"}, {"inserted", false}});
  j["meshes"].push_back(json{{"path", "statue.obj"}, {"inserted", true}});
  const Scene s = parseScene(j, "/scenes/test.json");
  ASSERT_EQ(s.meshes.size(), 3u);
  EXPECT_TRUE(s.meshes[0].inserted);  // the default
  EXPECT_FALSE(s.meshes[1].inserted);
  EXPECT_TRUE(s.meshes[2].inserted);

  // Only a JSON boolean: "false" as a string or 0 would otherwise read as a truthy or falsy
  // accident, so each is an error naming the field.
  for (const json& bad : {json("false"), json(0), json(nullptr), json::array({false})}) {
    json b = minimal();
    b["meshes"][0]["inserted"] = bad;
    try {
      parseScene(b, "/scenes/test.json");
      ADD_FAILURE() << "no error for inserted = " << bad.dump();
    } catch (const Error& e) {
      EXPECT_EQ(e.position(), "scene.meshes[0].inserted") << bad.dump();
      EXPECT_NE(std::string(e.what()).find("expected true or false"), std::string::npos)
          << e.what();
    }
  }
}

TEST(Scene, DisplaySettingsParse) {
  json j = minimal();
  Scene d = parseScene(j, "/scenes/test.json");
  EXPECT_FALSE(d.display.splatting);
  EXPECT_FALSE(d.display.pointSize);
  j["display"] = json{
      {"rasteriser", "points"}, {"splatting", "basic"}, {"point_size", 2.5}, {"edl_strength", 0}};
  Scene s = parseScene(j, "/scenes/test.json");
  EXPECT_EQ(s.display.rasteriser.value_or(""), "points");
  EXPECT_EQ(s.display.splatting.value_or(""), "basic");
  EXPECT_EQ(s.display.pointSize.value_or(0), 2.5f);
  EXPECT_EQ(s.display.edlStrength.value_or(-1), 0.f);
}

TEST(Scene, CamerasOfAPathAreInterpolatedPerFrame) {
  json j = minimal();
  j["camera_path"] = json{
      {"fps", 2},
      {"keyframes", json::array({json{{"time", 0}, {"eye", {0, 0, 0}}, {"target", {1, 0, 0}}},
                                 json{{"time", 1.5}, {"eye", {3, 0, 0}}, {"target", {4, 0, 0}}}})}};
  Scene s = parseScene(j, "/scenes/test.json");
  const auto cams = sceneCameras(s);
  ASSERT_EQ(cams.size(), 4u);  // t = 0, 0.5, 1, 1.5
  for (size_t f = 0; f < cams.size(); ++f) {
    EXPECT_DOUBLE_EQ(cams[f].eye.x, 2.0 * f * 0.5);  // eye x runs 0 to 3 over 1.5 s
    EXPECT_DOUBLE_EQ(cams[f].target.x, cams[f].eye.x + 1);
  }
  // `still` takes the scene's camera instead; without one it is an error naming the field.
  EXPECT_EQ(sceneCameras(s, true).size(), 1u);
  json noCamera = j;
  noCamera.erase("camera");
  try {
    sceneCameras(parseScene(noCamera, "/scenes/test.json"), true);
    ADD_FAILURE() << "no camera accepted";
  } catch (const nestlight::Error& e) {
    EXPECT_EQ(e.position(), "scene.camera");
  }
}

// Albedo mode needs something to emit: a scene of scans alone (the nave) is black there.
TEST(Scene, WhatLightsASceneDependsOnTheMode) {
  Scene s = parseScene(json::parse(R"({"octrees": ["scan.octree"],
      "materials": {"lamp": {"type": "lambert", "base_color": 0.5, "emission": [0, 0, 2]}},
      "meshes": [{"path": "x.obj", "material": {"type": "lambert", "base_color": 0.5}}]})"),
                       "/scenes/test.json");
  EXPECT_TRUE(sceneHasLight(s, RadianceMode::RadianceCache));
  EXPECT_FALSE(sceneHasLight(s, RadianceMode::Albedo));
  s.meshes[0].material = 0;  // the emissive material
  EXPECT_TRUE(sceneHasLight(s, RadianceMode::Albedo));
  s.meshes[0].material = 1;
  s.environment = SceneEnvironment{};
  EXPECT_TRUE(sceneHasLight(s, RadianceMode::Albedo));
  s.environment.reset();
  s.lights.push_back(Light{});
  EXPECT_TRUE(sceneHasLight(s, RadianceMode::Albedo));
}

TEST(Scene, ErrorsNameTheField) {
  auto with = [](const std::string& pointer, const json& v) {
    json j = minimal();
    j[json::json_pointer(pointer)] = v;
    return j;
  };
  EXPECT_EQ(errorField(with("/meshes/0/material", json{{"type", "ggx"}, {"roughness", 1.5}})),
            "scene.meshes[0].material.roughness");
  EXPECT_EQ(errorField(with("/meshes/0/material", json{{"type", "lambert"}, {"roughnes", 0.5}})),
            "scene.meshes[0].material.roughnes");  // a typo is not silently ignored
  EXPECT_EQ(errorField(with("/meshes/0/material", json{{"type", "lambert"}, {"metallic", 1}})),
            "scene.meshes[0].material.metallic");  // no effect on lambert: said, not ignored
  EXPECT_EQ(errorField(with("/meshes/0/material", "nosuch")), "scene.meshes[0].material");
  EXPECT_EQ(errorField(with("/meshes/0/transform", json{{"scale", 0}})),
            "scene.meshes[0].transform.scale");
  EXPECT_EQ(errorField(with("/meshes/0/transform", json{{"matrix", json::array({1, 2, 3})}})),
            "scene.meshes[0].transform.matrix");
  EXPECT_EQ(errorField(with("/lights", json::array({json{{"type", "area"}}}))),
            "scene.lights[0].type");
  EXPECT_EQ(errorField(with("/lights", json::array({json{{"type", "spot"},
                                                         {"position", {0, 0, 1}},
                                                         {"direction", {0, 0, 0}},
                                                         {"intensity", 1}}}))),
            "scene.lights[0].direction");
  EXPECT_EQ(
      errorField(
          with("/lights",
               json::array({json{{"type", "point"}, {"position", {0, 0, 1}}, {"intensity", -1}}}))),
      "scene.lights[0].intensity");
  EXPECT_EQ(errorField(with("/camera/width", 0)), "scene.camera.width");
  EXPECT_EQ(errorField(with("/camera/width", 1.5)), "scene.camera.width");
  EXPECT_EQ(errorField(with("/camera/target", json::array({0, -5, 1}))), "scene.camera.target");
  EXPECT_EQ(errorField(with("/camera/up", json::array({0, 10, -1}))),
            "scene.camera");  // parallel to the view
  EXPECT_EQ(errorField(with("/environment", json{{"path", "a.hdr"}, {"constant", 1}})),
            "scene.environment");
  EXPECT_EQ(errorField(with("/gi/mode", "photon")), "scene.gi.mode");
  EXPECT_EQ(errorField(with("/gi/samples_per_pixel", 0)), "scene.gi.samples_per_pixel");
  EXPECT_EQ(errorField(with("/octrees",
                            json::array({json{{"path", "a.octree"}, {"memory_budget", "lots"}}}))),
            "scene.octrees[0].memory_budget");
  EXPECT_EQ(
      errorField(with(
          "/camera_path",
          json{{"keyframes",
                json::array({json{{"time", 1}, {"eye", {0, 0, 0}}, {"target", {1, 0, 0}}},
                             json{{"time", 1}, {"eye", {0, 0, 0}}, {"target", {1, 0, 0}}}})}})),
      "scene.camera_path.keyframes[1].time");
  EXPECT_EQ(
      errorField(with("/lights", json::array({json{{"type", "spot"},
                                                   {"position", {0, 0, 1}},
                                                   {"direction", {0, 0, -1}},
                                                   {"intensity", 1},
                                                   {"inner_angle", 60}}}))),
      "scene.lights[0].inner_angle");  // wider than the default outer angle, which it does not name
  EXPECT_EQ(errorField(
                with("/octrees", json::array({json{{"path", "a"}, {"memory_budget", "1e30GiB"}}}))),
            "scene.octrees[0].memory_budget");
  EXPECT_EQ(errorField(with("/meshes/0/transform",
                            json{{"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1}}})),
            "scene.meshes[0].transform.matrix");  // projective
  EXPECT_EQ(
      errorField(with(
          "/camera_path",
          json{{"keyframes",
                json::array({json{{"time", 0}, {"eye", {0, 0, 0}}, {"target", {0, 0, -1}}}})}})),
      "scene.camera_path.keyframes[0]");  // looks along up
  EXPECT_EQ(errorField(with("/display", json{{"splatting", "gaussian"}})),
            "scene.display.splatting");
  EXPECT_EQ(errorField(with("/display", json{{"point_size", 0}})), "scene.display.point_size");
  EXPECT_EQ(errorField(with("/display", json{{"edl", 1}})), "scene.display.edl");
  EXPECT_EQ(errorField(with("/version", 2)), "scene.version");
  EXPECT_EQ(errorField(with("/colour", 1)), "scene.colour");
  EXPECT_EQ(errorField(json::object()), "scene");  // nothing to render
  EXPECT_EQ(errorField(json::array()), "scene");
}

TEST(Scene, FileErrorsGiveTheBytePosition) {
  test::TempDir dir;
  test::writeFile(dir.file("bad.json"), "{\n  \"meshes\": [\n    {\"path\": \"a.obj\",}\n  ]\n}\n");
  Error e = test::errorOf([&] { loadScene(dir.file("bad.json")); });
  EXPECT_EQ(e.file(), dir.file("bad.json"));
  EXPECT_NE(e.position().find("byte"), std::string::npos) << e.what();
  Error missing = test::errorOf([&] { loadScene(dir.file("none.json")); });
  EXPECT_NE(std::string(missing.what()).find("none.json"), std::string::npos);
  test::writeFile(dir.file("empty.json"), "");
  test::errorOf([&] { loadScene(dir.file("empty.json")); });
}

TEST(Scene, OriginDefaultsToTheFirstScanCentreOnlyWhenLoadedFromAFile) {
  json j = minimal();
  Scene s = parseScene(j, "/x/scene.json");
  EXPECT_FALSE(s.originSet);
  EXPECT_EQ(s.origin, glm::dvec3(0.0));
  resolveOrigin(s);  // no octree: stays 0
  EXPECT_EQ(s.origin, glm::dvec3(0.0));
}
