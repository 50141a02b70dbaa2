#include "nestlight/gi/camera_path.h"

#include <algorithm>
#include <cmath>

#include "nestlight/octree/error.h"
#include "nestlight/octree/json_field.h"

namespace nestlight::gi {

namespace {
constexpr double kMaxFrames = 1e6;

glm::dvec3 vec3(const JsonField& f) {
  const auto v = f.vec3();
  return {v[0], v[1], v[2]};
}
}  // namespace

int CameraPath::frames() const {
  if (keys.size() < 2) return 1;
  return int(std::floor((keys.back().time - keys.front().time) * fps + 1e-9)) + 1;
}

CameraKey CameraPath::at(int frame) const {
  NL_CHECK(!keys.empty());
  const double t = keys.front().time + frame / fps;
  size_t k = 0;
  while (k + 1 < keys.size() && keys[k + 1].time <= t) ++k;
  CameraKey c = keys[k];
  c.time = t;
  if (k + 1 < keys.size()) {
    const double a = std::clamp((t - keys[k].time) / (keys[k + 1].time - keys[k].time), 0.0, 1.0);
    c.eye = glm::mix(keys[k].eye, keys[k + 1].eye, a);
    c.target = glm::mix(keys[k].target, keys[k + 1].target, a);
  }
  return c;
}

CameraPath parseCameraPath(const JsonField& f, bool allowFov) {
  if (allowFov)
    f.expectObject({"fps", "fov", "keyframes"});
  else
    f.expectObject({"fps", "keyframes"});
  CameraPath p;
  if (f.has("fps")) p.fps = f.at("fps").number(0.001, 10000);
  if (allowFov && f.has("fov")) p.fovYDegrees = f.at("fov").number(0.01, 179);
  const JsonField keys = f.at("keyframes");
  for (size_t i = 0, n = keys.arraySize(); i < n; ++i) {
    const JsonField k = keys.at(i);
    k.expectObject({"time", "eye", "target"});
    if (!k.has("time") || !k.has("eye") || !k.has("target"))
      k.fail("a key needs \"time\", \"eye\" and \"target\"");
    CameraKey key{k.at("time").number(0, 1e6), vec3(k.at("eye")), vec3(k.at("target"))};
    if (!p.keys.empty() && !(key.time > p.keys.back().time))
      k.at("time").fail("key times must increase");
    if (!(glm::length(key.eye - key.target) > 0)) k.fail("eye and target coincide");
    p.keys.push_back(key);
  }
  if (p.keys.empty()) keys.fail("a camera path needs at least one key");
  // The product first: frames() converts it to int, which more than a million frames would
  // overflow.
  if ((p.keys.back().time - p.keys.front().time) * p.fps >= kMaxFrames)
    f.fail("asks for more than " + std::to_string(int(kMaxFrames)) + " frames");
  return p;
}

CameraPath loadCameraPath(const std::filesystem::path& file) {
  const nlohmann::json j = readJsonFile(file);
  return parseCameraPath(JsonField(j, "", file.string()), true);
}

}  // namespace nestlight::gi
