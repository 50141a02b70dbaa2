#include "nestlight/gi/hdr/views.h"

#include <cmath>
#include <fstream>
#include <numbers>

#include "nestlight/octree/error.h"
#include "nestlight/octree/json_field.h"
#include "nestlight/octree/octree_writer.h"

namespace nestlight::gi::hdr {

namespace fs = std::filesystem;
using json = nlohmann::json;

double View::focalPixels() const {
  return 0.5 * height / std::tan(0.5 * fovYDegrees * std::numbers::pi / 180.0);
}

bool View::project(const glm::dvec3& world, glm::dvec2& pixel, double& depth) const {
  const glm::dvec3 rel = world - position;
  depth = glm::dot(rel, forward);
  if (!(depth > 1e-9)) return false;
  const double f = focalPixels();
  pixel.x = 0.5 * width + f * glm::dot(rel, right()) / depth;
  pixel.y = 0.5 * height - f * glm::dot(rel, up) / depth;
  return true;
}

glm::dmat4 View::viewFromWorld() const {
  const glm::dvec3 r = right();
  glm::dmat4 m(1.0);
  // Rows are the camera's axes: x = right, y = up, z = -forward.
  for (int c = 0; c < 3; ++c) {
    m[c][0] = r[c];
    m[c][1] = up[c];
    m[c][2] = -forward[c];
  }
  m[3][0] = -glm::dot(r, position);
  m[3][1] = -glm::dot(up, position);
  m[3][2] = glm::dot(forward, position);
  return m;
}

glm::dmat4 View::clipFromView(double near, double far) const {
  const double t = std::tan(0.5 * fovYDegrees * std::numbers::pi / 180.0);
  const double aspect = double(width) / double(height);
  glm::dmat4 m(0.0);
  m[0][0] = 1.0 / (aspect * t);
  m[1][1] = 1.0 / t;
  m[2][2] = -(far + near) / (far - near);
  m[2][3] = -1.0;
  m[3][2] = -2.0 * far * near / (far - near);
  return m;
}

View lookAt(const glm::dvec3& position, const glm::dvec3& target, glm::dvec3 up, double fovYDegrees,
            int width, int height) {
  View v;
  v.position = position;
  glm::dvec3 f = target - position;
  if (glm::length(f) < 1e-12) f = {0, 1, 0};
  v.forward = glm::normalize(f);
  if (glm::length(glm::cross(v.forward, up)) < 1e-6)
    up = std::abs(v.forward.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(0, 1, 0);
  v.up = glm::normalize(up - glm::dot(up, v.forward) * v.forward);
  v.fovYDegrees = fovYDegrees;
  v.width = width;
  v.height = height;
  return v;
}

std::vector<View> cubeMap(const std::string& name, const glm::dvec3& position, int size) {
  const glm::dvec3 dirs[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  const glm::dvec3 ups[6] = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 1, 0}, {0, -1, 0}};
  const char* names[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};
  std::vector<View> out;
  for (int i = 0; i < 6; ++i) {
    View v = lookAt(position, position + dirs[i], ups[i], 90.0, size, size);
    v.name = name + names[i];
    out.push_back(v);
  }
  return out;
}

std::vector<View> readViews(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw Error(file.string(), "", "cannot open the views file");
  json j;
  try {
    j = json::parse(in);
  } catch (const json::parse_error& e) {
    throw Error(file.string(), Error::atByte(e.byte), "invalid JSON");
  }
  const JsonField root(j, "", file.string());
  root.expectObject({"views"});
  const JsonField list = root.at("views");
  std::vector<View> out;
  for (size_t i = 0, n = list.arraySize(); i < n; ++i) {
    const JsonField v = list.at(i);
    const std::string name = v.has("name") ? v.at("name").string() : "view" + std::to_string(i);
    if (v.has("cube_map")) {
      v.expectObject({"name", "cube_map", "size"});
      const auto p = v.at("cube_map").vec3();
      const int size = v.has("size") ? int(v.at("size").integer(8, 8192)) : 512;
      for (auto& face : cubeMap(name, {p[0], p[1], p[2]}, size)) out.push_back(face);
      continue;
    }
    v.expectObject({"name", "position", "look_at", "forward", "up", "fov_y", "width", "height",
                    "view_from_world", "clip_from_view"});
    const auto p = v.at("position").vec3();
    glm::dvec3 target;
    if (v.has("look_at")) {
      const auto t = v.at("look_at").vec3();
      target = {t[0], t[1], t[2]};
    } else {
      const auto f = v.at("forward").vec3();
      const glm::dvec3 fw{f[0], f[1], f[2]};
      if (glm::length(fw) < 1e-12) v.at("forward").fail("must not be zero");
      target = glm::dvec3(p[0], p[1], p[2]) + fw;
    }
    glm::dvec3 up{0, 0, 1};
    if (v.has("up")) {
      const auto u = v.at("up").vec3();
      up = {u[0], u[1], u[2]};
    }
    const double fov = v.has("fov_y") ? v.at("fov_y").number(1, 179) : 60.0;
    const int w = v.has("width") ? int(v.at("width").integer(8, 8192)) : 512;
    const int h = v.has("height") ? int(v.at("height").integer(8, 8192)) : 512;
    View view = lookAt({p[0], p[1], p[2]}, target, up, fov, w, h);
    view.name = name;
    out.push_back(view);
  }
  if (out.empty()) list.fail("lists no view");
  return out;
}

json viewToJson(const View& v) {
  auto vec = [](const glm::dvec3& a) { return json::array({a.x, a.y, a.z}); };
  auto mat = [](const glm::dmat4& m) {
    json rows = json::array();
    for (int r = 0; r < 4; ++r) rows.push_back(json::array({m[0][r], m[1][r], m[2][r], m[3][r]}));
    return rows;
  };
  return {{"name", v.name},
          {"position", vec(v.position)},
          {"forward", vec(v.forward)},
          {"up", vec(v.up)},
          {"fov_y", v.fovYDegrees},
          {"width", v.width},
          {"height", v.height},
          {"view_from_world", mat(v.viewFromWorld())},
          {"clip_from_view", mat(v.clipFromView(0.01, 1000.0))}};
}

void writeViews(const fs::path& file, const std::vector<View>& views) {
  json list = json::array();
  for (const auto& v : views) list.push_back(viewToJson(v));
  const std::string text = json{{"views", list}}.dump(2) + "\n";
  writeFileAtomic(file, text.data(), text.size());
}

}  // namespace nestlight::gi::hdr
