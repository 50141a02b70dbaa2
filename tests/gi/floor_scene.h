// The scene most GL method tests light: a 20 x 20 m floor (a flat box whose top face is z = 0)
// seen straight down from 6 m, in a square image; and where a pixel's ray meets that floor.
#pragma once

#include <cmath>
#include <fstream>
#include <glm/glm.hpp>
#include <nlohmann/json.hpp>
#include <vector>

#include "nestlight/converters/test_scenes.h"
#include "nestlight/gi/reference/path_tracer.h"
#include "nestlight/gi/scene.h"
#include "test_support.h"

namespace nestlight::gi {

// The floor (material "floor") and the camera; tests add materials, more meshes, lights,
// the environment and gi.
inline nlohmann::json floorSceneJson(const test::TempDir& t, int size) {
  writeBoxObj(t.path() / "box.obj");
  using json = nlohmann::json;
  return {{"version", 1},
          {"meshes",
           json::array({json{
               {"path", "box.obj"},
               {"transform", {{"translate", {-10.0, -10.0, -0.1}}, {"scale", {20.0, 20.0, 0.1}}}},
               {"material", "floor"}}})},
          {"camera",
           {{"eye", {0.0, -0.001, 6.0}},
            {"target", {0.0, 0.0, 0.0}},
            {"up", {0.0, 1.0, 0.0}},
            {"fov", 60.0},
            {"width", size},
            {"height", size}}}};
}

// The far-mesh shadow tests' scene on the floor: a 1 x 1 x 0.2 m plate 1 m up (its umbra spans
// x in [-1.7, -0.5], |y| < 0.5), optionally a sunlit wall facing it at x = -3 (the floor's
// indirect light), all of lambert material "floor" (albedo 0.5), under a sun of irradiance `E`
// along (-1, 0, -1).
inline void addPlateUnderSun(nlohmann::json& j, float E, bool wall) {
  using json = nlohmann::json;
  j["meshes"].push_back(
      json{{"path", "box.obj"},
           {"transform", {{"translate", {-0.5, -0.5, 1.0}}, {"scale", {1.0, 1.0, 0.2}}}},
           {"material", "floor"}});
  if (wall)
    j["meshes"].push_back(
        json{{"path", "box.obj"},
             {"transform", {{"translate", {-3.2, -9.0, 0.0}}, {"scale", {0.2, 18.0, 2.0}}}},
             {"material", "floor"}});
  j["materials"] = {{"floor", {{"type", "lambert"}, {"base_color", 0.5}}}};
  j["lights"] = json::array(
      {json{{"type", "directional"}, {"direction", {-1.0, 0.0, -1.0}}, {"irradiance", {E, E, E}}}});
}

// A 20 m box 1000 km from the floor: out of every test camera's view.
inline nlohmann::json farBox() {
  return {{"path", "box.obj"},
          {"transform", {{"translate", {1.0e6, 0.0, 0.0}}, {"scale", 20.0}}},
          {"material", "floor"}};
}

// Where the ray through pixel (x + 0.5, y + 0.5) meets the plane z = 0 (the reference's camera),
// when that is on the floor within `half` of its centre.
inline bool floorPoint(const Scene& s, int x, int y, glm::vec3* p, float half = 9.5f) {
  glm::vec3 o, d;
  cameraRay(s.camera, s.origin, x + 0.5f, y + 0.5f, &o, &d);
  if (!(d.z < 0)) return false;
  *p = o + d * (-o.z / d.z);
  return std::abs(p->x) < half && std::abs(p->y) < half;
}

// A Lambert floor of albedo 0.5 under `lights`, optionally a 1 x 1 m occluder 1 m
// above it.
inline Scene lambertFloorScene(const test::TempDir& t, const nlohmann::json& lights, int size = 64,
                               bool occluder = false) {
  nlohmann::json j = floorSceneJson(t, size);
  if (occluder)
    j["meshes"].push_back(nlohmann::json{
        {"path", "box.obj"},
        {"transform", {{"translate", {-0.5, -0.5, 1.0}}, {"scale", {1.0, 1.0, 0.2}}}},
        {"material", "floor"}});
  j["materials"] = {{"floor", {{"type", "lambert"}, {"base_color", 0.5}}}};
  j["lights"] = lights;
  j["gi"] = {{"method", "raster"}, {"mode", "albedo"}, {"parameters", {{"shadow_map_size", 1024}}}};
  std::ofstream(t.path() / "scene.json") << j.dump(2);
  return loadScene(t.path() / "scene.json");
}

// A scan point as the GI tests write them: position, normal, 8-bit sRGB colour.
struct ScanPoint {
  glm::vec3 position, normal;
  int red, green, blue;
};

// `points` as an ASCII PLY with normals and colours (what the converter reads as a scan).
inline void writeScanPly(const std::string& file, const std::vector<ScanPoint>& points) {
  std::ofstream ply(file);
  ply << "ply\nformat ascii 1.0\nelement vertex " << points.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty "
         "float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\nproperty uchar "
         "blue\nend_header\n";
  for (const ScanPoint& q : points)
    ply << q.position.x << " " << q.position.y << " " << q.position.z << " " << q.normal.x << " "
        << q.normal.y << " " << q.normal.z << " " << q.red << " " << q.green << " " << q.blue
        << "\n";
}

}  // namespace nestlight::gi
