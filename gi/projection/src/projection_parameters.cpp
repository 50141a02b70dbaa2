// `projection`'s declaration: its parameters and its entry in the registry.
#include "nestlight/gi/frame/frame_parameters.h"
#include "nestlight/gi/method_info.h"
#include "nestlight/gi/projection/projection_method.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/json_field.h"

namespace nestlight::gi {

const ParameterSpecs& projectionParameterSpecs() {
  using P = ParameterSpec;
  static const ParameterSpecs specs = {
      P::integer("points", 1, 1 << 22, 262144,
                 "the point set S: the lights' cut thinned to at most this many points (whole "
                 "levels from the root, then every k-th point of the next)"),
      P::integer("clusters", 1, 512, 512,
                 "clusters of S (equal counts, median splits), each given one importance")
          .powersOfTwo(),
      P::integer("random_per_cluster", 1, 8, 2,
                 "random points per cluster and receiver: the cluster's importance (eq. 1), "
                 "splatted too"),
      P::integer("samples_per_cluster", 0, 8, 4,
                 "importance samples per cluster on average: N_s = this x clusters, shared among "
                 "the clusters by importance"),
      P::integer("micro_buffer", 8, 32, 32,
                 "texels per side of a receiver's hemi-octahedral micro-buffer"),
      P::choice("sampling", {"importance", "random", "brute"}, "importance",
                "importance (the paper), random (uniform over S) or brute (all of S: the "
                "micro-buffer's reference)")
          .asFlag(),
      P::integer("splat", 1, 3, "adaptive",
                 "splat side in texels: adaptive (the solid angle a sample stands for, eq. 3) or "
                 "a fixed 1, 2 or 3")
          .orOneOf({"adaptive"}),
      P::integer("fill", 0, 4, 2,
                 "passes closing holes between splats: an empty texel covered on two opposite "
                 "sides takes its nearer neighbour's sample (0: the paper's micro-buffers)"),
      P::boolean("adaptive", true,
                 "image-space adaptive sampling: gather a grid, then where the coherence metric "
                 "says so, upsampling the rest (false: every receiver pixel gathers)"),
      P::integer("grid", 1, 16, 4, "the first level's grid step in pixels").powersOfTwo(),
      P::integer("levels", 0, 8, 0,
                 "the adaptive sampling's levels that gather (0: all); the finer ones are only "
                 "interpolated from them: the images the viewer shows as it refines"),
      P::number(
          "progressive_ms", 0, 1e5, 33,
          "the viewer: each frame gathers the grid, then the finer levels' pixels for at most "
          "this long; while the view rests, frames go on where the last stopped, up to the "
          "still's image (0: every frame gathers all)"),
      P::number("lambda", 0, 1e6, 8, "the metric's weight of radiance changes against geometry"),
      P::number("epsilon", 0, 1e6, 0.3,
                "the metric's threshold: a pixel gathers where the metric reaches it (0: every "
                "pixel)"),
      P::number("epsilon_level_factor", 1e-3, 1e3, 2,
                "epsilon's factor per level below the first (the paper: \"scaled by 2\")"),
      P::integer("post_filter", 0, 7, "auto",
                 "the joint bilateral post filter's window: auto (7 x 7, 3 x 3 where glossy), 0 "
                 "(none), 3 or 7")
          .orOneOf({"auto"}),
      P::boolean("glossy_to_glossy", true,
                 "glossy meshes' surfels reflect their 4 strongest lights in glossy lobes toward "
                 "each receiver, and weigh their importance so (false: all points diffuse)"),
      P::integer("supersample", 1, 2, 1,
                 "stills at 2 x 2 subpixels a pixel, box-filtered (the paper's 2xAA; about 4x "
                 "the time; the viewer's frames stay at 1)"),
      P::pixels("dump_pixels", 256,
                "pixels whose micro-buffers each still writes as EXR (texel light; which texels "
                "a sample covers in the header), e.g. [[80, 60]]"),
      [] {
        ParameterSpec p;
        p.name = "dump_folder";
        p.type = ParameterType::String;
        p.defaultValue = "";
        p.help = "the folder dump_pixels writes to (default: micro-buffers beside the scene file)";
        return p;
      }(),
      P::integer("bounce_receivers", 1, 1 << 22, 4096,
                 "albedo mode, gi.max_bounces 3 and more: the points of S that gather each "
                 "further bounce (the others take the nearest one's of their cluster)"),
  };
  return specs;
}

ProjectionParameters projectionParameters(const Scene& scene) {
  const ResolvedParameters r = resolveParameterValues(scene, projectionParameterSpecs());
  ProjectionParameters p;
  p.points = int(r.integer("points"));
  p.clusters = int(r.integer("clusters"));
  p.randomPerCluster = int(r.integer("random_per_cluster"));
  p.samplesPerCluster = int(r.integer("samples_per_cluster"));
  p.microBuffer = int(r.integer("micro_buffer"));
  const std::string s = r.string("sampling");
  p.sampling = s == "random"  ? ProjectionParameters::Sampling::Random
               : s == "brute" ? ProjectionParameters::Sampling::Brute
                              : ProjectionParameters::Sampling::Importance;
  const nlohmann::json& splat = r.value("splat");
  p.splat = splat.is_string() ? 0 : int(splat.get<int64_t>());
  p.fillPasses = int(r.integer("fill"));
  p.adaptive = r.boolean("adaptive");
  p.grid = int(r.integer("grid"));
  p.lambda = float(r.number("lambda"));
  p.epsilon = float(r.number("epsilon"));
  p.epsilonLevelFactor = float(r.number("epsilon_level_factor"));
  p.levels = int(r.integer("levels"));
  p.progressiveMs = r.number("progressive_ms");
  p.bounceReceivers = int(r.integer("bounce_receivers"));
  p.supersample = int(r.integer("supersample"));
  p.glossyToGlossy = r.boolean("glossy_to_glossy");
  for (const nlohmann::json& px : r.value("dump_pixels"))
    p.dumpPixels.push_back({px[0].get<int>(), px[1].get<int>()});
  p.dumpFolder = r.string("dump_folder");
  if (p.dumpFolder.empty()) p.dumpFolder = (scene.file.parent_path() / "micro-buffers").string();
  const nlohmann::json& filter = r.value("post_filter");
  p.postFilter = filter.is_string() ? -1 : int(filter.get<int64_t>());
  if (p.postFilter != -1 && p.postFilter != 0 && p.postFilter != 3 && p.postFilter != 7) {
    const JsonField params(scene.gi.parameters, "scene.gi.parameters", scene.file.string());
    params.at("post_filter").fail("expected auto, 0, 3 or 7, got " + std::to_string(p.postFilter));
  }
  // A receiver's samples are told apart by 12 bits of its depth words.
  const int samples = p.clusters * (p.randomPerCluster + p.samplesPerCluster);
  if (samples > 4096) {
    const JsonField params(scene.gi.parameters, "scene.gi.parameters", scene.file.string());
    std::string key = "clusters";
    for (const char* k : {"samples_per_cluster", "random_per_cluster"})
      if (params.value().contains(k)) key = k;
    params.at(key).fail("clusters x (random_per_cluster + samples_per_cluster) is " +
                        std::to_string(samples) +
                        " samples per receiver; at most 4096 fit the micro-buffer's depth words");
  }
  return p;
}

std::string microBufferFileName(int x, int y) {
  return "projection_" + std::to_string(x) + "_" + std::to_string(y) + ".exr";
}

MethodInfo projectionMethodInfo() {
  MethodInfo m;
  m.name = "projection";
  m.summary = "real-time GI: importance-driven point projection into per-pixel micro-buffers (GL)";
  m.gpu = true;
  m.qualityName = "importance samples per cluster";
  // The 8 does not fit: 512 clusters x (2 random + 8) is 5,120 samples a receiver, and
  // the micro-buffer's depth words tell 4,096 apart (llvmpipe has no 64-bit atomics); 6 fills
  // them exactly.
  m.defaultQualities = {1, 2, 4, 6};
  m.applyQuality = [](GiSettings& g, int q) { setParameter(g, "samples_per_cluster", q); };
  m.create = createProjectionMethod;
  // The variants but brute force (all of S per pixel: minutes a frame, and beyond 65,535
  // points llvmpipe's loop limit cuts it short; `bench projection` measures it where it is the
  // micro-buffers' reference).
  const MethodInfo::Applicability albedoOnly = [](const Scene& s) -> std::string {
    return s.gi.mode == RadianceMode::Albedo
               ? ""
               : "the radiance-cache mode has one bounce: the scan's colour is its light";
  };
  m.variants = {
      {"random", [](GiSettings& g) { g.parameters["sampling"] = "random"; }},
      {"splat 1", [](GiSettings& g) { g.parameters["splat"] = 1; }},
      {"splat 2", [](GiSettings& g) { g.parameters["splat"] = 2; }},
      {"splat 3", [](GiSettings& g) { g.parameters["splat"] = 3; }},
      {"every pixel", [](GiSettings& g) { g.parameters["adaptive"] = false; }},
      {"grid", [](GiSettings& g) { g.parameters["levels"] = 1; }},
      {"1 bounce", [](GiSettings& g) { g.maxBounces = std::min(g.maxBounces, 2); }, albedoOnly},
      {"no glossy-to-glossy", [](GiSettings& g) { g.parameters["glossy_to_glossy"] = false; },
       [](const Scene& s) -> std::string {
         for (const SceneMesh& m : s.meshes)
           if (m.material < s.materials.size() &&
               s.materials[m.material].type != MaterialType::Lambert)
             return "";
         return "no glossy mesh: every point reflects diffusely either way";
       }}};
  m.parameters = rasterParameterSpecs();
  m.parameters.insert(m.parameters.end(), projectionParameterSpecs().begin(),
                      projectionParameterSpecs().end());
  return m;
}

}  // namespace nestlight::gi
