// Test scenes for GI (issue 4): synthetic scans of a Cornell-like room, a nave and a town, with
// inserted meshes; see test_scenes.h.
#include "nestlight/converters/test_scenes.h"

#include <array>
#include <cmath>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <vector>

#include "nestlight/converters/builder.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/octree/error.h"

namespace nestlight {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

struct ObjMesh {
  std::vector<std::array<double, 3>> v;
  std::vector<std::array<uint32_t, 3>> f;
};

void writeObj(const fs::path& path, const ObjMesh& m, const std::string& comment) {
  fs::path tmp = path;
  tmp += ".partial";
  {
    std::ofstream out(tmp);
    if (!out) throw Error(path.string(), "", "cannot write");
    out << "# " << comment << "\n";
    char buf[128];
    for (const auto& v : m.v) {
      std::snprintf(buf, sizeof buf, "v %.9g %.9g %.9g\n", v[0], v[1], v[2]);
      out << buf;
    }
    for (const auto& f : m.f) out << "f " << f[0] + 1 << ' ' << f[1] + 1 << ' ' << f[2] + 1 << '\n';
    if (!out) throw Error(path.string(), "", "write failed");
  }
  fs::rename(tmp, path);
}

}  // namespace

void writeIcosphereObj(const fs::path& path, int subdivisions) {
  // Icosahedron, then each triangle split in four with the new vertices pushed onto the sphere.
  const double t = (1 + std::sqrt(5.0)) / 2;
  ObjMesh m;
  m.v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
         {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  m.f = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
         {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
         {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  auto normalise = [](std::array<double, 3>& p) {
    double l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (double& c : p) c /= l;
  };
  for (auto& p : m.v) normalise(p);
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      std::array<double, 3> p{(m.v[a][0] + m.v[b][0]) / 2, (m.v[a][1] + m.v[b][1]) / 2,
                              (m.v[a][2] + m.v[b][2]) / 2};
      normalise(p);
      m.v.push_back(p);
      return mid[key] = uint32_t(m.v.size() - 1);
    };
    std::vector<std::array<uint32_t, 3>> next;
    for (const auto& f : m.f) {
      uint32_t a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      next.push_back({f[0], a, c});
      next.push_back({f[1], b, a});
      next.push_back({f[2], c, b});
      next.push_back({a, b, c});
    }
    m.f = std::move(next);
  }
  writeObj(path, m,
           "unit icosphere, " + std::to_string(subdivisions) + " subdivisions (nestlight)");
}

void writeTorusObj(const fs::path& path, double R, double r, int segments, int sides) {
  ObjMesh m;
  const double tau = 2 * std::numbers::pi;
  for (int i = 0; i < segments; ++i)
    for (int j = 0; j < sides; ++j) {
      double u = tau * i / segments, v = tau * j / sides;
      m.v.push_back({(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u),
                     r * std::sin(v)});
    }
  auto id = [&](int i, int j) { return uint32_t((i % segments) * sides + (j % sides)); };
  for (int i = 0; i < segments; ++i)
    for (int j = 0; j < sides; ++j) {
      m.f.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.f.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  writeObj(path, m, "torus R=" + std::to_string(R) + " r=" + std::to_string(r) + " (nestlight)");
}

void writeBoxObj(const fs::path& path) {
  ObjMesh m;
  for (int i = 0; i < 8; ++i)
    m.v.push_back({double(i & 1), double((i >> 1) & 1), double((i >> 2) & 1)});
  // Counter-clockwise seen from outside.
  m.f = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
         {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  writeObj(path, m, "unit box [0,1]^3 (nestlight)");
}

namespace {

using MeshWrites = std::vector<std::function<void()>>;

json cameraJson(std::array<double, 3> eye, std::array<double, 3> target, double fov,
                const TestSceneOptions& o) {
  return json{
      {"eye", eye}, {"target", target}, {"fov", fov}, {"width", o.width}, {"height", o.height}};
}

// The cornell room's scan: a 4 m room whose recorded colour is its albedo (the ceiling patch,
// the cornell scene's light, is the brightest).
void cornellScan(SyntheticSpec& spec) {
  spec.shape = SyntheticShape::Room;
  spec.size = 4;
  spec.noise = 0.001;
}

// Differential rendering's ground truth (Rohmer, Jendersie, Grosch, "Natural Environment
// Illumination: Coherent Interactive Augmented Reality for Mobile and non-Mobile Devices", 2017):
// the captured room and its light are one scene, the object on the floor is what is inserted.
// The room is rendered in albedo mode, so its light must come from something that emits: the
// captured panel (a mesh that is not inserted) or a spot light.
void diffrenderScene(json& scene, SyntheticSpec& spec, MeshWrites& meshWrites, const fs::path& dir,
                     const TestSceneOptions& o) {
  cornellScan(spec);
  // The room's free floor is the corner x, y > 2.2 beyond its two blocks; the object stands at
  // (2.6, 2.6) (the cornell sphere's place), the light hangs over the room's centre, under the
  // scan's ceiling patch (z 3.98).
  const fs::path bunny = o.sharedData.empty() ? fs::path() : o.sharedData / "meshes" / "bunny.ply";
  json object;
  if (!bunny.empty() && fs::is_regular_file(bunny)) {
    meshWrites.push_back([bunny, dir] {
      // A fresh, writable copy: the shared file may be read-only, and its mode comes with it.
      fs::remove(dir / "bunny.ply");
      fs::copy_file(bunny, dir / "bunny.ply");
      fs::permissions(dir / "bunny.ply", fs::perms::owner_write, fs::perm_options::add);
    });
    // The Stanford bunny is y-up in metres, x -0.095..0.061, y 0.033..0.187, z -0.062..0.059:
    // turned z-up, scaled to 0.62 m tall, turned to show the camera its face in three-quarter
    // view, its feet on the floor (z 0.033 * 4) and its box centred at (2.6, 2.6).
    object = {
        {"path", "bunny.ply"},
        {"transform",
         {{"translate", {2.639, 2.688, -0.132}}, {"rotate", {90.0, 0.0, 75.0}}, {"scale", 4.0}}}};
  } else {
    meshWrites.push_back([dir] { writeIcosphereObj(dir / "object.obj", 3); });
    object = {{"path", "object.obj"},
              {"transform", {{"translate", {2.6, 2.6, 0.3}}, {"scale", 0.3}}}};
  }
  object["material"] = "bronze";
  object["inserted"] = true;
  scene["materials"] = {{"bronze", {{"type", "lambert"}, {"base_color", {0.7, 0.6, 0.45}}}}};
  scene["meshes"] = json::array({object});
  if (o.light == DiffrenderLight::Spot) {
    // Straight down: the inner cone (30 degrees) covers the object, the outer (60) the floor.
    scene["lights"] = json::array({json{{"type", "spot"},
                                        {"position", {2.0, 2.0, 3.9}},
                                        {"direction", {0.0, 0.0, -1.0}},
                                        {"intensity", 10.0},
                                        {"inner_angle", 30.0},
                                        {"outer_angle", 60.0}}});
  } else {
    // A 2 m square panel 5 cm thick: straight down as bright as the spot (radiance x area =
    // 10 W/sr). Wide and dim rather than small and bright: a path tracer that finds it only by
    // hitting it converges four times faster than on a 1 m panel of the same power.
    meshWrites.push_back([dir] { writeBoxObj(dir / "panel.obj"); });
    scene["materials"]["panel"] = {
        {"type", "lambert"}, {"base_color", 0.8}, {"emission", {2.5, 2.5, 2.5}}};
    scene["meshes"].push_back(
        json{{"path", "panel.obj"},
             {"transform", {{"translate", {1.0, 1.0, 3.9}}, {"scale", {2.0, 2.0, 0.05}}}},
             {"material", "panel"},
             {"inserted", false}});
  }
  // From the free corner, down at the object and the floor round it, the blocks behind.
  scene["camera"] = cameraJson({3.7, 3.7, 1.5}, {2.5, 2.5, 0.25}, 50, o);
  // The scan's colours are albedos; the capture diffrender adds to is the colour layer
  // `captured` that make-scene bakes with the reference (nestlight bake-radiance). Eight
  // scattering events: the material estimate (eq. 5) divides a point's captured radiance (k
  // events) by the light its neighbours' captured radiance brings (k + 1), so a short capture
  // reads as a darker albedo: at 3 the floor's true material came out 1.1% lower than at 8.
  scene["gi"] = {{"method", "diffrender"},
                 {"mode", "albedo"},
                 {"max_bounces", 8},
                 {"samples_per_pixel", 1024},
                 {"target_relative_error", 0.01},
                 {"parameters", {{"capture", "captured"}}}};
}

}  // namespace

std::optional<TestSceneKind> parseTestSceneKind(const std::string& name) {
  if (name == "cornell") return TestSceneKind::Cornell;
  if (name == "diffrender") return TestSceneKind::Diffrender;
  if (name == "nave") return TestSceneKind::Nave;
  if (name == "object") return TestSceneKind::Object;
  return std::nullopt;
}

const char* testSceneKindName(TestSceneKind kind) {
  switch (kind) {
    case TestSceneKind::Cornell:
      return "cornell";
    case TestSceneKind::Nave:
      return "nave";
    case TestSceneKind::Object:
      return "object";
    case TestSceneKind::Diffrender:
      return "diffrender";
  }
  return "?";
}

fs::path makeTestScene(TestSceneKind kind, const fs::path& dir, const TestSceneOptions& o) {
  MeshWrites meshWrites;  // after the checks below: nothing is touched before
  SyntheticSpec spec;
  spec.points = o.points;
  spec.seed = o.seed;
  spec.intensity = false;
  spec.normals = true;  // the reference's discs need them; real scans get --estimate-normals
  json scene;
  scene["version"] = 1;
  scene["octrees"] = json::array({json{{"path", "scan.octree"}}});
  auto camera = [&](std::array<double, 3> eye, std::array<double, 3> target, double fov) {
    return cameraJson(eye, target, fov, o);
  };
  switch (kind) {
    case TestSceneKind::Cornell: {
      cornellScan(spec);
      meshWrites.push_back([dir] { writeIcosphereObj(dir / "sphere.obj", 3); });
      scene["materials"] = {{"glossy",
                             {{"type", "ggx"},
                              {"base_color", {0.9, 0.8, 0.6}},
                              {"roughness", 0.35},
                              {"metallic", 0.0}}}};
      scene["meshes"] =
          json::array({json{{"path", "sphere.obj"},
                            {"transform", {{"translate", {2.6, 2.6, 0.5}}, {"scale", 0.5}}},
                            {"material", "glossy"},
                            {"surfels", {{"method", "area"}, {"count", 20000}}}}});
      // A lamp under the light patch: it lights the sphere in both modes, and the whole room in
      // the albedo mode, where the scan's recorded light does not emit.
      scene["lights"] =
          json::array({json{{"type", "point"}, {"position", {2.0, 2.0, 3.7}}, {"intensity", 6.0}}});
      scene["camera"] = camera({2.0, 0.12, 3.2}, {2.2, 3.0, 0.5}, 68);
      scene["gi"] = {{"method", "reference"},
                     {"mode", "radiance_cache"},
                     {"max_bounces", 4},
                     {"samples_per_pixel", 1024},
                     {"target_relative_error", 0.01}};
      break;
    }
    case TestSceneKind::Nave: {
      spec.shape = SyntheticShape::Nave;
      spec.size = 40;  // 40 x 20 x 12 m
      spec.noise = 0.003;
      meshWrites.push_back([dir] { writeIcosphereObj(dir / "statue.obj", 3); });
      meshWrites.push_back([dir] { writeBoxObj(dir / "pedestal.obj"); });
      scene["materials"] = {{"marble",
                             {{"type", "principled"},
                              {"base_color", {0.85, 0.83, 0.8}},
                              {"roughness", 0.3},
                              {"specular", 0.5},
                              {"clearcoat", 0.3}}},
                            {"stone", {{"type", "lambert"}, {"base_color", {0.5, 0.48, 0.45}}}}};
      scene["meshes"] = json::array(
          {json{{"path", "pedestal.obj"},
                {"transform", {{"translate", {23.0, 9.0, 0.0}}, {"scale", {2.0, 2.0, 1.2}}}},
                {"material", "stone"}},
           json{{"path", "statue.obj"},
                {"transform", {{"translate", {24.0, 10.0, 2.2}}, {"scale", 1.0}}},
                {"material", "marble"}}});
      scene["camera"] = camera({4.0, 10.0, 3.0}, {30.0, 10.0, 3.5}, 55);
      scene["gi"] = {{"method", "reference"},
                     {"mode", "radiance_cache"},
                     {"max_bounces", 4},
                     {"samples_per_pixel", 1024},
                     {"target_relative_error", 0.01}};
      break;
    }
    case TestSceneKind::Object: {
      spec.shape = SyntheticShape::Surfaces;
      spec.size = 100;
      meshWrites.push_back([dir] { writeTorusObj(dir / "torus.obj", 1.0, 0.35, 64, 24); });
      scene["materials"] = {{"gold",
                             {{"type", "ggx"},
                              {"base_color", {1.0, 0.78, 0.34}},
                              {"roughness", 0.25},
                              {"metallic", 1.0}}}};
      scene["meshes"] = json::array(
          {json{{"path", "torus.obj"},
                {"transform",
                 {{"translate", {50.0, 45.0, 5.0}}, {"rotate", {60.0, 0.0, 20.0}}, {"scale", 3.0}}},
                {"material", "gold"}}});
      scene["lights"] = json::array({json{{"type", "directional"},
                                          {"direction", {-0.4, -0.3, -0.87}},
                                          {"irradiance", {3.0, 2.9, 2.7}}}});
      scene["environment"] = {{"constant", {0.35, 0.45, 0.6}}};
      // From the street between the two buildings (x 42..55), looking north at the torus.
      scene["camera"] = camera({48.5, 20.0, 10.0}, {50.0, 45.0, 5.0}, 50);
      scene["gi"] = {{"method", "reference"},
                     {"mode", "albedo"},
                     {"max_bounces", 3},
                     {"samples_per_pixel", 1024},
                     {"target_relative_error", 0.01}};
      break;
    }
    case TestSceneKind::Diffrender:
      diffrenderScene(scene, spec, meshWrites, dir, o);
      break;
  }
  scene["output"] = {{"exr", std::string(testSceneKindName(kind)) + ".exr"},
                     {"png", std::string(testSceneKindName(kind)) + ".png"}};

  // What the scan is made from: an octree in the folder is reused only when it was made from
  // exactly this (a nave's scan never stands in a cornell scene), and a scene file that differs
  // from this one (edited, or another scene's) is replaced only with `overwrite`.
  const json stamp = {{"kind", testSceneKindName(kind)}, {"points", o.points}, {"seed", o.seed}};
  const std::string text = scene.dump(2) + "\n";
  const fs::path file = dir / "scene.json", octree = dir / "scan.octree",
                 stampFile = dir / "scene-source.json";
  auto read = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const bool haveOctree = fs::exists(octree / "metadata.json");
  json oldStamp;
  if (fs::exists(stampFile)) oldStamp = json::parse(read(stampFile), nullptr, false);
  const bool sameScan = haveOctree && oldStamp == stamp;
  if (!o.overwrite) {
    if (fs::exists(file) && read(file) != text)
      throw Error(file.string(), "",
                  "differs from the " + std::string(testSceneKindName(kind)) +
                      " scene make-scene writes (edited, or another scene's); pass --overwrite to "
                      "replace the folder's "
                      "scene, meshes and scan");
    if (haveOctree && !sameScan)
      throw Error(octree.string(), "",
                  "was not made for this scene (" +
                      (oldStamp.is_object() ? oldStamp.dump() : std::string("unknown source")) +
                      ", not " + stamp.dump() + "); pass --overwrite to rebuild it");
  }
  fs::create_directories(dir);
  for (const auto& w : meshWrites) w();
  if (o.overwrite || !sameScan) {
    fs::remove(stampFile);
    BuildOptions b;
    b.output = octree;
    b.overwrite = true;
    b.progress = o.quiet ? ProgressMode::Quiet : ProgressMode::Auto;
    std::vector<std::unique_ptr<PointReader>> sources;
    sources.push_back(openSynthetic(spec));
    buildOctree(std::move(sources), b);
    std::ofstream(stampFile) << stamp.dump(1) << "\n";
  }
  std::ofstream out(file);
  out << text;
  if (!out) throw Error(file.string(), "", "cannot write the scene file");
  return file;
}

}  // namespace nestlight
