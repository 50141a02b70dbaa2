// Scene files (docs/SCENE.md). Validation is strict: an unknown key is an error (a typo in
// "roughnes" must not silently fall back to a default), and every error names the field by its
// JSON path.
#include "nestlight/gi/scene.h"

#include <cmath>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <set>
#include <sstream>

#include "nestlight/gi/environment_sequence.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/json_field.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight::gi {
namespace {

using json = nlohmann::json;

// The shared validator (nestlight/octree/json_field.h) with the scene's own value types.
class Field : public JsonField {
 public:
  Field(const json& j, std::string path, const std::string& file)
      : JsonField(j, std::move(path), file) {}
  explicit Field(const JsonField& f) : JsonField(f) {}
  Field at(const std::string& key) const { return Field(JsonField::at(key)); }
  Field at(size_t i) const { return Field(JsonField::at(i)); }

  glm::dvec3 vec3(double lo = -INFINITY, double hi = INFINITY) const {
    const auto v = JsonField::vec3(lo, hi);
    return {v[0], v[1], v[2]};
  }
  // A colour: [r, g, b] or a single number for grey.
  Rgb colour(double lo = 0, double hi = INFINITY) const {
    if (value().is_number()) return Rgb(float(number(lo, hi)));
    return Rgb(vec3(lo, hi));
  }
  glm::dvec3 direction() const {
    glm::dvec3 d = vec3();
    double len = glm::length(d);
    if (!(len > 1e-12)) fail("a direction must not be the zero vector");
    return d / len;
  }
  uint64_t bytes() const {
    if (value().is_number()) return uint64_t(number(1, 1e18));
    std::string s = string();
    char* end = nullptr;
    double v = std::strtod(s.c_str(), &end);
    std::string unit(end);
    double mul = 0;
    if (unit.empty() || unit == "B")
      mul = 1;
    else if (unit == "KiB" || unit == "K")
      mul = 1024.0;
    else if (unit == "MiB" || unit == "M")
      mul = 1024.0 * 1024;
    else if (unit == "GiB" || unit == "G")
      mul = 1024.0 * 1024 * 1024;
    if (mul == 0 || !(v > 0) || end == s.c_str() || !std::isfinite(v * mul) || v * mul > 1e18)
      fail("expected a size such as \"512MiB\" or \"2GiB\", got '" + s + "'");
    return uint64_t(v * mul);
  }
};

std::filesystem::path resolvePath(const Field& f, const std::filesystem::path& sceneFile) {
  std::filesystem::path p = f.string();
  if (p.empty()) f.fail("a path must not be empty");
  if (p.is_relative()) p = sceneFile.parent_path() / p;
  return p.lexically_normal();
}

glm::dmat4 parseTransform(const Field& f) {
  f.expectObject({"translate", "rotate", "scale", "matrix"});
  if (f.has("matrix")) {
    if (f.has("translate") || f.has("rotate") || f.has("scale"))
      f.fail("give either \"matrix\" or translate/rotate/scale, not both");
    Field m = f.at("matrix");
    if (m.arraySize() != 16)
      m.fail("expected 16 numbers (row-major 4x4), got " + std::to_string(m.arraySize()));
    glm::dmat4 r(1.0);
    for (int row = 0; row < 4; ++row)
      for (int col = 0; col < 4; ++col) r[col][row] = m.at(size_t(row * 4 + col)).number();
    if (std::abs(glm::determinant(glm::dmat3(r))) < 1e-18) m.fail("the matrix is singular");
    if (r[0][3] != 0 || r[1][3] != 0 || r[2][3] != 0 || r[3][3] != 1)
      m.fail(
          "the last row must be 0, 0, 0, 1 (an affine transform; projective ones are not meshes' "
          "transforms)");
    return r;
  }
  glm::dmat4 t(1.0);
  if (f.has("translate")) t = glm::translate(t, f.at("translate").vec3());
  if (f.has("rotate")) {
    // Degrees about x, then y, then z (applied to the object in that order).
    glm::dvec3 r = glm::radians(f.at("rotate").vec3(-36000, 36000));
    t = glm::rotate(t, r.z, glm::dvec3(0, 0, 1));
    t = glm::rotate(t, r.y, glm::dvec3(0, 1, 0));
    t = glm::rotate(t, r.x, glm::dvec3(1, 0, 0));
  }
  if (f.has("scale")) {
    Field s = f.at("scale");
    glm::dvec3 v = s.value().is_number() ? glm::dvec3(s.number(1e-12, 1e12)) : s.vec3(1e-12, 1e12);
    t = glm::scale(t, v);
  }
  return t;
}

Material parseMaterial(const Field& f, const std::string& name) {
  f.expectObject({"type", "base_color", "roughness", "metallic", "specular", "specular_tint",
                  "sheen", "sheen_tint", "clearcoat", "clearcoat_gloss", "emission"});
  Material m;
  m.name = name;
  std::string type =
      f.has("type") ? f.at("type").choice({"lambert", "ggx", "principled"}) : "lambert";
  m.type = type == "ggx"          ? MaterialType::GGX
           : type == "principled" ? MaterialType::Principled
                                  : MaterialType::Lambert;
  if (f.has("base_color")) m.baseColor = f.at("base_color").colour(0, 1);
  auto unit = [&](const char* key, float& out) {
    if (f.has(key)) out = float(f.at(key).number(0, 1));
  };
  unit("roughness", m.roughness);
  unit("metallic", m.metallic);
  unit("specular", m.specular);
  unit("specular_tint", m.specularTint);
  unit("sheen", m.sheen);
  unit("sheen_tint", m.sheenTint);
  unit("clearcoat", m.clearcoat);
  unit("clearcoat_gloss", m.clearcoatGloss);
  if (f.has("emission")) m.emission = f.at("emission").colour(0, 1e30);
  if (m.type == MaterialType::Lambert) {
    for (const char* k : {"roughness", "metallic", "specular", "specular_tint", "sheen",
                          "sheen_tint", "clearcoat", "clearcoat_gloss"})
      if (f.has(k))
        f.at(k).fail(
            std::string("'") + k +
            "' has no effect on a lambert material (use \"type\": \"ggx\" or \"principled\")");
  } else if (m.type == MaterialType::GGX) {
    for (const char* k :
         {"specular", "specular_tint", "sheen", "sheen_tint", "clearcoat", "clearcoat_gloss"})
      if (f.has(k))
        f.at(k).fail(std::string("'") + k +
                     "' is a principled parameter (use \"type\": \"principled\")");
  }
  return m;
}

Light parseLight(const Field& f) {
  if (!f.value().is_object()) f.fail("expected an object");
  if (!f.has("type")) f.fail("missing \"type\" (point, spot or directional)");
  std::string type = f.at("type").choice({"point", "spot", "directional"});
  Light l;
  if (type == "point") {
    f.expectObject({"type", "position", "intensity"});
    l.type = LightType::Point;
  } else if (type == "spot") {
    f.expectObject({"type", "position", "direction", "intensity", "inner_angle", "outer_angle"});
    l.type = LightType::Spot;
  } else {
    f.expectObject({"type", "direction", "irradiance"});
    l.type = LightType::Directional;
  }
  if (l.type != LightType::Directional) {
    if (!f.has("position")) f.fail("missing \"position\"");
    l.position = f.at("position").vec3();
    if (!f.has("intensity")) f.fail("missing \"intensity\" (W/sr, a number or [r, g, b])");
    l.intensity = f.at("intensity").colour(0, 1e30);
  } else {
    if (!f.has("irradiance"))
      f.fail("missing \"irradiance\" (W/m^2 on a surface facing the light)");
    l.intensity = f.at("irradiance").colour(0, 1e30);
  }
  if (l.type != LightType::Point) {
    if (!f.has("direction")) f.fail("missing \"direction\"");
    l.direction = glm::vec3(f.at("direction").direction());
  }
  if (l.type == LightType::Spot) {
    if (f.has("inner_angle")) l.innerAngleDegrees = float(f.at("inner_angle").number(0, 179));
    if (f.has("outer_angle")) l.outerAngleDegrees = float(f.at("outer_angle").number(0, 179));
    if (l.outerAngleDegrees < l.innerAngleDegrees)
      (f.has("outer_angle") ? f.at("outer_angle") : f.at("inner_angle"))
          .fail("outer_angle (" + std::to_string(l.outerAngleDegrees) +
                ") must not be smaller than inner_angle (" + std::to_string(l.innerAngleDegrees) +
                ")");
  }
  return l;
}

SceneCamera parseCamera(const Field& f) {
  f.expectObject({"eye", "target", "up", "fov", "width", "height"});
  SceneCamera c;
  if (!f.has("eye") || !f.has("target")) f.fail("a camera needs \"eye\" and \"target\"");
  c.eye = f.at("eye").vec3();
  c.target = f.at("target").vec3();
  if (glm::length(c.target - c.eye) < 1e-12) f.at("target").fail("target equals eye");
  if (f.has("up")) c.up = f.at("up").direction();
  if (!viewIsValid(c.eye, c.target, c.up)) f.fail("the view direction is parallel to \"up\"");
  if (f.has("fov")) c.fovYDegrees = f.at("fov").number(0.01, 179);
  if (f.has("width")) c.width = int(f.at("width").integer(1, 16384));
  if (f.has("height")) c.height = int(f.at("height").integer(1, 16384));
  return c;
}

}  // namespace

bool viewIsValid(const glm::dvec3& eye, const glm::dvec3& target, const glm::dvec3& up) {
  glm::dvec3 d = target - eye;
  double len = glm::length(d);
  return len > 1e-12 && glm::length(glm::cross(d / len, glm::normalize(up))) > 1e-9;
}

glm::mat4 Scene::localFromObject(const SceneMesh& m) const {
  glm::dmat4 localFromWorld = glm::translate(glm::dmat4(1.0), -origin);
  return glm::mat4(localFromWorld * m.worldFromObject);
}

namespace {

SceneOctree parseOctree(Field o, const std::filesystem::path& file) {
  SceneOctree t;
  if (o.value().is_string()) {
    t.path = resolvePath(o, file);
  } else {
    o.expectObject({"path", "max_level", "memory_budget", "radius_scale", "colour_scale", "colour",
                    "clipping"});
    if (!o.has("path")) o.fail("missing \"path\"");
    t.path = resolvePath(o.at("path"), file);
    if (o.has("max_level")) t.maxLevel = int(o.at("max_level").integer(0, 30));
    if (o.has("memory_budget")) t.memoryBudget = o.at("memory_budget").bytes();
    if (o.has("radius_scale")) t.radiusScale = float(o.at("radius_scale").number(0, 100));
    if (o.has("colour_scale")) t.colourScale = float(o.at("colour_scale").number(0, 1e9));
    if (o.has("clipping"))
      t.clipping = ClipSet::fromJson(nlohmann::json{{"clipping", o.at("clipping").value()}},
                                     file.string() + ": " + o.path());
    if (o.has("colour")) {
      Field c = o.at("colour");
      if (!c.value().is_string() || c.value().get<std::string>().empty())
        c.fail("expected \"rgb\" or the name of a colour layer of the octree (\"hdr\")");
      t.colour = c.value().get<std::string>();
      // A layer the octree lacks fails here, naming the field, not later in a method.
      std::error_code ec;
      if (t.colour != "rgb" && std::filesystem::exists(t.path / "metadata.json", ec)) {
        const OctreeReader reader(t.path);
        const LayerRecord* layer = reader.metadata().layer(t.colour);
        if (!layer)
          c.fail("the octree has no colour layer '" + t.colour +
                 "' (nestlight expand-hdr makes \"hdr\")");
        if (layer->kind != "colour")
          c.fail("layer '" + t.colour + "' holds '" + layer->kind + "', not colour");
      }
    }
  }
  return t;
}

// A mesh; a material given inline (or none: the default) is appended to `materials`.
SceneMesh parseMesh(Field o, size_t i, const std::filesystem::path& file,
                    const std::map<std::string, uint32_t>& materialIndex,
                    std::vector<Material>& materials) {
  o.expectObject({"path", "transform", "material", "surfels", "inserted"});
  SceneMesh mesh;
  if (!o.has("path")) o.fail("missing \"path\" (a .ply or .obj file)");
  mesh.path = resolvePath(o.at("path"), file);
  if (o.has("transform")) mesh.worldFromObject = parseTransform(o.at("transform"));
  if (o.has("material")) {
    Field mf = o.at("material");
    if (mf.value().is_string()) {
      auto it = materialIndex.find(mf.string());
      if (it == materialIndex.end())
        mf.fail("no material named '" + mf.string() + "' in \"materials\"");
      mesh.material = it->second;
    } else {
      mesh.material = uint32_t(materials.size());
      materials.push_back(parseMaterial(mf, "meshes[" + std::to_string(i) + "]"));
    }
  } else {
    mesh.material = uint32_t(materials.size());
    materials.push_back(Material{});
  }
  if (o.has("surfels")) {
    Field sf = o.at("surfels");
    sf.expectObject({"method", "count"});
    if (sf.has("method"))
      mesh.surfelMethod = sf.at("method").choice({"area", "poisson"}) == "poisson"
                              ? SurfelSampling::PoissonDisk
                              : SurfelSampling::AreaUniform;
    if (sf.has("count")) mesh.surfelCount = size_t(sf.at("count").integer(1, 100'000'000));
  }
  if (o.has("inserted")) mesh.inserted = o.at("inserted").boolean();
  return mesh;
}

SceneEnvironment parseEnvironment(Field e, const std::filesystem::path& file) {
  e.expectObject({"path", "constant", "sequence", "fps", "on_bad_frame", "rotation", "scale"});
  SceneEnvironment env;
  if (int(e.has("path")) + int(e.has("constant")) + int(e.has("sequence")) != 1)
    e.fail(
        "give exactly one of \"path\" (EXR or HDR lat-long), \"constant\" and \"sequence\" (a "
        "frame "
        "pattern such as probe_%04d.exr, or a folder)");
  if (e.has("path")) env.path = resolvePath(e.at("path"), file);
  if (e.has("sequence")) {
    env.sequence = resolvePath(e.at("sequence"), file);
    if (e.has("fps")) env.fps = e.at("fps").number(1e-6, 1e6);
    if (e.has("on_bad_frame")) {
      Field b = e.at("on_bad_frame");
      const std::string v = b.value().is_string() ? b.value().get<std::string>() : "";
      if (v != "error" && v != "previous") b.fail("expected \"error\" or \"previous\"");
      env.keepPreviousOnBadFrame = v == "previous";
    }
    // The frames are listed now, so a sequence that names none fails with its field.
    try {
      EnvironmentSequence probe(sequenceSpec(env));
    } catch (const Error& x) {
      e.at("sequence").fail(x.what());
    }
  } else if (e.has("fps") || e.has("on_bad_frame")) {
    e.fail("\"fps\" and \"on_bad_frame\" belong to a \"sequence\"");
  }
  if (e.has("constant")) env.constant = e.at("constant").colour(0, 1e30);
  if (e.has("rotation")) env.rotationDegrees = float(e.at("rotation").number(-36000, 36000));
  if (e.has("scale")) env.scale = float(e.at("scale").number(0, 1e30));
  return env;
}

GiSettings parseGi(Field g) {
  GiSettings gi;
  g.expectObject({"method", "mode", "max_bounces", "samples_per_pixel", "target_relative_error",
                  "time_limit", "seed", "parameters"});
  // Which names are methods is the registry's to say (gi/methods' checkSceneMethod): the scene
  // file's name is checked there, before any override replaces it.
  if (g.has("method")) gi.method = g.at("method").string();
  if (g.has("mode"))
    gi.mode = g.at("mode").choice({"radiance_cache", "albedo"}) == "albedo"
                  ? RadianceMode::Albedo
                  : RadianceMode::RadianceCache;
  if (g.has("max_bounces")) gi.maxBounces = int(g.at("max_bounces").integer(0, 64));
  if (g.has("samples_per_pixel"))
    gi.samplesPerPixel = int(g.at("samples_per_pixel").integer(1, 1 << 24));
  if (g.has("target_relative_error"))
    gi.targetRelativeError = g.at("target_relative_error").number(0, 1);
  if (g.has("time_limit")) gi.timeLimitSeconds = g.at("time_limit").number(0, 1e7);
  if (g.has("seed")) gi.seed = uint64_t(g.at("seed").integer(0, INT64_MAX));
  if (g.has("parameters")) {
    if (!g.at("parameters").value().is_object()) g.at("parameters").fail("expected an object");
    gi.parameters = g.at("parameters").value();
  }
  return gi;
}

}  // namespace

Scene parseScene(const json& j, const std::filesystem::path& file) {
  const std::string fileName = file.string();
  Field root(j, "scene", fileName);
  root.expectObject({"version", "origin", "octrees", "materials", "meshes", "lights", "environment",
                     "camera", "camera_path", "gi", "display", "output"});
  Scene s;
  s.file = file;
  if (root.has("version") && root.at("version").integer(1, 1000) != 1)
    root.at("version").fail("this nestlight reads scene version 1");
  if (root.has("origin")) {
    s.origin = root.at("origin").vec3();
    s.originSet = true;
  }
  if (root.has("octrees")) {
    Field a = root.at("octrees");
    for (size_t i = 0; i < a.arraySize(); ++i) {
      s.octrees.push_back(parseOctree(a.at(i), file));
    }
  }
  std::map<std::string, uint32_t> materialIndex;
  if (root.has("materials")) {
    Field m = root.at("materials");
    if (!m.value().is_object()) m.fail("expected an object of named materials");
    for (auto it = m.value().begin(); it != m.value().end(); ++it) {
      materialIndex[it.key()] = uint32_t(s.materials.size());
      s.materials.push_back(parseMaterial(m.at(it.key()), it.key()));
    }
  }
  if (root.has("meshes")) {
    Field a = root.at("meshes");
    for (size_t i = 0; i < a.arraySize(); ++i) {
      s.meshes.push_back(parseMesh(a.at(i), i, file, materialIndex, s.materials));
    }
  }
  if (root.has("lights")) {
    Field a = root.at("lights");
    for (size_t i = 0; i < a.arraySize(); ++i) s.lights.push_back(parseLight(a.at(i)));
  }
  if (root.has("environment")) {
    s.environment = parseEnvironment(root.at("environment"), file);
  }
  if (root.has("camera")) {
    s.camera = parseCamera(root.at("camera"));
    s.cameraSet = true;
  }
  if (root.has("camera_path")) {
    s.cameraPath = parseCameraPath(root.at("camera_path"), false);
    const Field keys = root.at("camera_path").at("keyframes");
    for (size_t i = 0; i < s.cameraPath.keys.size(); ++i)
      if (!viewIsValid(s.cameraPath.keys[i].eye, s.cameraPath.keys[i].target, s.camera.up))
        keys.at(i).fail("eye equals target, or the view is parallel to \"up\"");
  }
  if (root.has("gi")) {
    s.gi = parseGi(root.at("gi"));
  }
  if (root.has("display")) {
    Field d = root.at("display");
    d.expectObject({"rasteriser", "splatting", "point_size", "edl_strength"});
    if (d.has("rasteriser"))
      s.display.rasteriser = d.at("rasteriser").choice({"points", "compute"});
    if (d.has("splatting")) s.display.splatting = d.at("splatting").choice({"hqs", "basic"});
    if (d.has("point_size")) s.display.pointSize = float(d.at("point_size").number(0.05, 64));
    if (d.has("edl_strength")) s.display.edlStrength = float(d.at("edl_strength").number(0, 100));
  }
  if (root.has("output")) {
    Field o = root.at("output");
    o.expectObject({"exr", "png", "exposure"});
    if (o.has("exr")) s.output.exr = resolvePath(o.at("exr"), file);
    if (o.has("png")) s.output.png = resolvePath(o.at("png"), file);
    if (o.has("exposure")) {
      s.output.exposure = o.at("exposure").number(-64, 64);
      s.output.exposureSet = true;
    }
  }
  if (s.octrees.empty() && s.meshes.empty()) root.fail("a scene needs at least one octree or mesh");
  return s;
}

bool sceneHasLight(const Scene& scene, RadianceMode mode) {
  if (mode == RadianceMode::RadianceCache && !scene.octrees.empty()) return true;
  if (!scene.lights.empty() || scene.environment) return true;
  for (const auto& m : scene.meshes)
    if (m.material < scene.materials.size()) {
      const Rgb& e = scene.materials[m.material].emission;
      if (e.r > 0 || e.g > 0 || e.b > 0) return true;
    }
  return false;
}

EnvironmentSequenceSpec sequenceSpec(const SceneEnvironment& e) {
  EnvironmentSequenceSpec spec;
  spec.source = e.sequence;
  spec.fps = e.fps;
  spec.rotationDegrees = e.rotationDegrees;
  spec.scale = e.scale;
  spec.keepPreviousOnBadFrame = e.keepPreviousOnBadFrame;
  return spec;
}

EnvironmentMap loadEnvironmentAt(const SceneEnvironment& e, double seconds) {
  if (e.sequence.empty()) return EnvironmentMap::load(e.path.string(), e.rotationDegrees, e.scale);
  EnvironmentSequence seq(sequenceSpec(e));
  return *seq.frame(seq.frameAt(seconds));
}

std::vector<SceneCamera> sceneCameras(const Scene& scene, bool still) {
  const std::string file = scene.file.string();
  std::vector<SceneCamera> cameras;
  if (scene.cameraPath.empty() || still) {
    if (!scene.cameraSet)
      throw Error(file, "scene.camera", "missing: a render needs a camera (or a camera_path)");
    if (!still && scene.environment && !scene.environment->sequence.empty()) {
      const EnvironmentSequence seq(sequenceSpec(*scene.environment));
      for (size_t f = 0; f < seq.frames(); ++f) {
        SceneCamera c = scene.camera;
        // The middle of the frame's interval: floor(time * fps) is f however fps rounds.
        c.time = (double(f) + 0.5) / seq.fps();
        cameras.push_back(c);
      }
      return cameras;
    }
    cameras.push_back(scene.camera);
    return cameras;
  }
  const int frames = scene.cameraPath.frames();
  for (int f = 0; f < frames; ++f) {
    const CameraKey k = scene.cameraPath.at(f);
    SceneCamera c = scene.camera;
    c.eye = k.eye;
    c.target = k.target;
    c.time = double(f) / scene.cameraPath.fps;
    if (!viewIsValid(c.eye, c.target, c.up))
      throw Error(file, "scene.camera_path",
                  "frame " + std::to_string(f) +
                      ": eye meets target or looks along \"up\" between keyframes");
    cameras.push_back(c);
  }
  return cameras;
}

Scene loadScene(const std::filesystem::path& file) {
  const json j = readJsonFile(file);
  Scene s = parseScene(j, std::filesystem::absolute(file));
  resolveOrigin(s);
  return s;
}

void resolveOrigin(Scene& scene) {
  if (scene.originSet || scene.octrees.empty()) return;
  OctreeReader reader(scene.octrees.front().path);
  const Box3d& b = reader.metadata().bounds;
  scene.origin = {(b.min.x + b.max.x) / 2, (b.min.y + b.max.y) / 2, (b.min.z + b.max.z) / 2};
  scene.originSet = true;
}

}  // namespace nestlight::gi
