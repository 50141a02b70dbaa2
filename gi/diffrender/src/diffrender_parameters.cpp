// `diffrender`'s declaration: its parameters, the quality presets of the paper's Table 2 and its
// entry in the registry.
#include <algorithm>
#include <array>
#include <filesystem>
#include <glm/gtc/matrix_inverse.hpp>

#include "nestlight/gi/diffrender/diffrender_method.h"
#include "nestlight/gi/frame/frame_parameters.h"
#include "nestlight/gi/method_info.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/json_field.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight::gi {

namespace {

// A grid of object voxels is at most this many bytes on the GPU (occupancy and surface words with
// their mips): one SSBO range's worth, as every buffer of the frame.
constexpr double kMaxVolumeBytes = double(128 << 20);

// Table 2 of the paper: what a preset sets when the scene does not set it itself.
nlohmann::json presetValues(DiffrenderParameters::Quality q) {
  using Q = DiffrenderParameters::Quality;
  if (q == Q::Low)
    return {{"samples", 16}, {"cache", 8}, {"object_voxels", 32}, {"self_shadow", false}};
  if (q == Q::Med)
    return {{"samples", 16}, {"cache", 8}, {"object_voxels", 32}, {"self_shadow", true}};
  return {{"samples", 64},         {"cache", 32},
          {"object_samples", 128}, {"object_voxels", {128, 96, 96}},
          {"self_shadow", true},   {"secondary_bounce", true}};
}

glm::ivec3 parseVoxels(const JsonField& f) {
  if (f.value().is_array()) {
    if (f.arraySize() != 3) f.fail("expected an integer or [x, y, z]");
    return {int(f.at(size_t(0)).integer(2, 1024)), int(f.at(size_t(1)).integer(2, 1024)),
            int(f.at(size_t(2)).integer(2, 1024))};
  }
  return glm::ivec3(int(f.integer(2, 1024)));
}

ParameterSpec captureSpec() {
  ParameterSpec p;
  p.name = "capture";
  p.type = ParameterType::String;
  p.defaultValue = "";
  p.help =
      "the colour layer of captured radiance (nestlight bake-radiance writes one), whatever "
      "gi.mode; empty: the scan's colour in the radiance-cache mode";
  return p;
}

ParameterSpec stringSpec(const char* name, const char* help) {
  ParameterSpec p;
  p.name = name;
  p.type = ParameterType::String;
  p.defaultValue = "";
  p.help = help;
  return p;
}

// colour-match's C as 3 rows of 3 numbers, or a file holding colour-match --json's report (its
// "matrix").
glm::mat3 parseColourMap(const JsonField& f) {
  if (f.value().is_string()) {
    std::filesystem::path file(f.string());
    if (file.is_relative()) file = std::filesystem::path(f.file()).parent_path() / file;
    nlohmann::json report;
    try {
      report = readJsonFile(file);
    } catch (const Error& e) {
      f.fail(std::string("cannot read the colour map: ") + e.what());
    }
    if (!report.is_object() || !report.contains("matrix"))
      f.fail(file.string() + " has no \"matrix\" (colour-match --json writes one)");
    const JsonField matrix(report.at("matrix"), "matrix", file.string());
    if (!matrix.value().is_array()) matrix.fail("expected 3 rows of 3 numbers");
    return parseColourMap(matrix);
  }
  if (!f.value().is_array() || f.arraySize() != 3)
    f.fail("expected 3 rows of 3 numbers (colour-match's C) or a colour-match --json file");
  glm::mat3 m(1.0f);
  for (size_t r = 0; r < 3; ++r) {
    const JsonField row = f.at(r);
    if (!row.value().is_array() || row.arraySize() != 3) row.fail("expected 3 numbers");
    for (size_t c = 0; c < 3; ++c) m[int(c)][int(r)] = float(row.at(c).number());
  }
  if (!(std::abs(glm::determinant(m)) > 1e-9f))
    f.fail(
        "the map is singular: the composite could not be brought back into the photograph's "
        "colours");
  return m;
}

ParameterSpec aovsSpec() {
  ParameterSpec p;
  p.name = "aovs";
  p.type = ParameterType::String;
  p.defaultValue = "";
  p.help =
      "a folder for each still's dL, rho and mask EXRs (diffrender_delta.exr, diffrender_rho.exr, "
      "diffrender_mask.exr), relative to the scene file; empty: none";
  return p;
}

}  // namespace

const char* queryName(DiffrenderParameters::Query q) {
  switch (q) {
    case DiffrenderParameters::Query::Em:
      return "em";
    case DiffrenderParameters::Query::Dit:
      return "dit";
    case DiffrenderParameters::Query::Vct:
      return "vct";
    case DiffrenderParameters::Query::Exact:
      return "exact";
  }
  return "?";
}

const char* qualityName(DiffrenderParameters::Quality q) {
  switch (q) {
    case DiffrenderParameters::Quality::Low:
      return "low";
    case DiffrenderParameters::Quality::Med:
      return "med";
    case DiffrenderParameters::Quality::High:
      return "high";
  }
  return "?";
}

const ParameterSpecs& diffrenderParameterSpecs() {
  using P = ParameterSpec;
  static const ParameterSpecs specs = {
      P::choice("query", {"dit", "em", "vct", "exact"}, "dit",
                "how rays find the scene's light: dit (distance impostor tracing, default), em "
                "(lookup by direction), vct (voxel cones), exact (rays)")
          .asFlag(),
      P::choice("quality", {"low", "med", "high"}, "med",
                "the paper's presets (Table 2) for the keys not given: low 16 samples, cache 8, "
                "32^3 voxels, no self-shadow; med adds self-shadow; high 64 samples, cache 32, 128 "
                "object samples, 128x96x96 voxels, a secondary bounce")
          .asFlag(),
      P::integer("samples", 1, 1024, 16,
                 "N: cosine directions per scan pixel, for the material and dL"),
      P::integer("object_samples", 1, 1024, 16, "BRDF samples per pixel of an inserted mesh"),
      P::integer("cache", 1, 1024, 8,
                 "hits of the objects' box traced per scan pixel, the rest counted (eq. 9)"),
      P::integer("object_voxels", 2, 1024, 32,
                 "the inserted meshes' solid voxel grid: n (n^3) or [x, y, z]"),
      P::boolean("self_shadow", true, "object rays march the object volume (blocked: ambient)"),
      P::boolean("secondary_bounce", false,
                 "object rays their own volume blocks see the light the hit voxel sends back (its "
                 "normal and material) instead of ambient"),
      P::integer("impostor_size", 16, 4096, 256, "texels of a distance impostor's cube face"),
      P::integer("scene_voxels", 16, 512, 256, "vct: the scene volume's voxels per axis"),
      P::integer("delta_scale", 1, 8, 2, "dL is computed at 1/delta_scale of the resolution"),
      P::number("ambient", 0, 1e30, 0, "radiance of an object ray its own mesh blocks"),
      P::number("rho_max", 0.01, 1e3, 1, "the material estimate is clamped here (counted)"),
      P::choice("material", {"estimate", "colour"}, "estimate",
                "the scan's reflectance: estimate (eq. 5) or the recorded colour (an ablation)"),
      aovsSpec(),
      captureSpec(),
      stringSpec("background",
                 "a photograph of the camera's view (.exr/.hdr linear, .png display) to composite "
                 "onto instead of the capture; empty: the capture"),
      stringSpec("background_map",
                 "colour-match's 3x3 map C from the photograph's colours into the scan's (3 rows "
                 "of 3 numbers, or a colour-match --json file); default identity"),
      P::integer("dit_iterations", 1, 64, 8,
                 "DIT: refinements of a ray's lookup direction before it counts as unconverged"),
      stringSpec("impostor_centre",
                 "[x, y, z] in the scene's coordinates (the meshes' frame): where the distance "
                 "impostor is drawn from; default the middle of the inserted meshes' boxes (move "
                 "it into open space when that middle falls inside the scan, as between two "
                 "meshes set far apart)"),
      P::boolean("compare_exact", false,
                 "an accuracy check of the query: each material ray is also traced exactly and the "
                 "query's hits within an impostor texel's footprint of the exact hit are counted "
                 "(costs exact's time)"),
  };
  return specs;
}

DiffrenderParameters diffrenderParameters(const Scene& scene) {
  const nlohmann::json& given =
      scene.gi.parameters.is_object() ? scene.gi.parameters : nlohmann::json::object();
  // object_voxels may be [x, y, z], which the integer declaration does not read: resolve the rest
  // without it.
  Scene rest = scene;
  const JsonField params(scene.gi.parameters, "scene.gi.parameters", scene.file.string());
  if (given.contains("object_voxels")) rest.gi.parameters.erase("object_voxels");
  if (given.contains("background_map")) rest.gi.parameters.erase("background_map");
  if (given.contains("impostor_centre")) rest.gi.parameters.erase("impostor_centre");
  const ResolvedParameters r = resolveParameterValues(rest, diffrenderParameterSpecs());
  DiffrenderParameters p;
  const std::string q = r.string("query"), quality = r.string("quality");
  using Q = DiffrenderParameters::Query;
  p.query = q == "dit" ? Q::Dit : q == "em" ? Q::Em : q == "vct" ? Q::Vct : Q::Exact;
  using L = DiffrenderParameters::Quality;
  p.quality = quality == "low" ? L::Low : quality == "med" ? L::Med : L::High;
  const nlohmann::json preset = presetValues(p.quality);
  auto pick = [&](const char* key) -> nlohmann::json {
    if (given.contains(key)) return given.at(key);
    if (preset.contains(key)) return preset.at(key);
    return r.value(key);
  };
  p.samples = pick("samples").get<int>();
  p.objectSamples = pick("object_samples").get<int>();
  p.cache = pick("cache").get<int>();
  if (given.contains("object_voxels")) {
    p.objectVoxels = parseVoxels(params.at("object_voxels"));
  } else {
    const nlohmann::json v = preset.value("object_voxels", nlohmann::json(32));
    p.objectVoxels = v.is_array() ? glm::ivec3(v[0].get<int>(), v[1].get<int>(), v[2].get<int>())
                                  : glm::ivec3(v.get<int>());
  }
  p.selfShadow = pick("self_shadow").get<bool>();
  p.secondaryBounce = pick("secondary_bounce").get<bool>();
  p.impostorSize = int(r.integer("impostor_size"));
  p.sceneVoxels = int(r.integer("scene_voxels"));
  p.deltaScale = int(r.integer("delta_scale"));
  p.ambient = float(r.number("ambient"));
  p.rhoMax = float(r.number("rho_max"));
  p.materialEstimate = r.string("material") == "estimate";
  p.ditIterations = int(r.integer("dit_iterations"));
  p.compareExact = r.boolean("compare_exact");
  if (const std::string a = r.string("aovs"); !a.empty()) {
    const std::filesystem::path dir(a);
    p.aovs = (dir.is_absolute() ? dir : scene.file.parent_path() / dir).string();
  }
  p.capture = r.string("capture");
  if (const std::string b = r.string("background"); !b.empty()) {
    const std::filesystem::path photo(b);
    p.background = (photo.is_absolute() ? photo : scene.file.parent_path() / photo).string();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(p.background, ec))
      params.at("background").fail("no such file: " + p.background);
  }
  if (given.contains("background_map"))
    p.backgroundMap = parseColourMap(params.at("background_map"));
  if (given.contains("impostor_centre")) {
    const std::array<double, 3> c = params.at("impostor_centre").vec3(-1e12, 1e12);
    p.impostorCentre = glm::dvec3(c[0], c[1], c[2]);
  }
  // A cache the scene gives must fit its samples; a preset's shrinks to them (high's 32 at 16
  // samples traces all 16).
  if (p.cache > p.samples && !given.contains("cache")) p.cache = p.samples;
  if (p.cache > p.samples)
    params.at("cache").fail("cache (" + std::to_string(p.cache) + ") must not exceed samples (" +
                            std::to_string(p.samples) +
                            "): it is how many of the samples' hits are traced");
  const double voxels = double(p.objectVoxels.x) * p.objectVoxels.y * p.objectVoxels.z;
  // R8 occupancy and RGBA8 surface, each with its mips (8/7 of the finest level).
  if (voxels * 5.0 * 8.0 / 7.0 > kMaxVolumeBytes)
    (given.contains("object_voxels") ? params.at("object_voxels") : params)
        .fail("the object volume would take " +
              std::to_string(int(voxels * 5.0 * 8.0 / 7.0 / 1e6)) +
              " MB, over the 128 MiB bound: use fewer voxels");
  return p;
}

Scene diffrenderCaptureScene(const Scene& scene, const DiffrenderParameters& p) {
  if (p.capture.empty()) {
    if (scene.gi.mode == RadianceMode::Albedo)
      throw Error(scene.file.string(), "scene.gi.mode",
                  "diffrender adds to a capture of the scan's radiance, and in the albedo mode "
                  "the scan's colour is its albedo: give gi.parameters.capture, a colour layer of "
                  "captured radiance (nestlight bake-radiance scene.json --layer captured), or use "
                  "the radiance-cache mode");
    return scene;
  }
  Scene s = scene;
  const JsonField field(scene.gi.parameters, "scene.gi.parameters", scene.file.string());
  for (size_t i = 0; i < s.octrees.size(); ++i) {
    const OctreeReader reader(s.octrees[i].path);
    const LayerRecord* layer = reader.metadata().layer(p.capture);
    if (!layer || layer->kind != "colour")
      field.at("capture").fail("octrees[" + std::to_string(i) + "] (" + s.octrees[i].path.string() +
                               ") has no colour layer '" + p.capture +
                               "' (nestlight bake-radiance scene.json --layer " + p.capture +
                               " writes it)");
    s.octrees[i].colour = p.capture;
    s.octrees[i].colourScale = 1;  // the layer holds radiance
  }
  s.gi.mode = RadianceMode::RadianceCache;
  return s;
}

MethodInfo diffrenderMethodInfo() {
  MethodInfo m;
  m.name = "diffrender";
  m.summary =
      "differential rendering: inserted meshes lit from the captured scan, their shadows and "
      "bounce added to it (distance impostors; GL)";
  m.gpu = true;
  m.qualityName = "samples per scan pixel";
  m.defaultQualities = {8, 16, 64};
  m.applyQuality = [](GiSettings& g, int q) {
    setParameter(g, "samples", q);
    // A cache the scene gives shrinks to the samples (a preset's does so by itself).
    if (g.parameters.contains("cache") && g.parameters["cache"].is_number_integer() &&
        g.parameters["cache"].get<int>() > q)
      setParameter(g, "cache", q);
  };
  m.create = createDiffrenderMethod;
  // The capture is the scan's recorded colour (radiance-cache mode) or a layer of it.
  m.whyNotApplicable = [](const Scene& s) -> std::string {
    if (s.gi.mode == RadianceMode::Albedo &&
        !(s.gi.parameters.is_object() && s.gi.parameters.contains("capture")))
      return "in the albedo mode it needs gi.parameters.capture, a layer of captured radiance "
             "(nestlight bake-radiance)";
    for (const SceneMesh& mesh : s.meshes)
      if (mesh.inserted) return "";
    return "the scene has no inserted mesh (meshes[].inserted), and diffrender's work is the "
           "change an inserted mesh makes";
  };
  m.variants = {{"em", [](GiSettings& g) { g.parameters["query"] = "em"; }},
                {"vct", [](GiSettings& g) { g.parameters["query"] = "vct"; }},
                {"low", [](GiSettings& g) { g.parameters["quality"] = "low"; }},
                {"high", [](GiSettings& g) { g.parameters["quality"] = "high"; }}};
  m.parameters = rasterParameterSpecs();
  m.parameters.insert(m.parameters.end(), diffrenderParameterSpecs().begin(),
                      diffrenderParameterSpecs().end());
  return m;
}

}  // namespace nestlight::gi
