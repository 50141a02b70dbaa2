#include <algorithm>

#include "nestlight/gi/ibl/ibl_method.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/pbgi/pbgi_method.h"
#include "nestlight/gi/raster/raster_method.h"
#include "nestlight/gi/vpl/vpl_method.h"
#include "nestlight/octree/error.h"
#include "reference_method.h"

namespace nestlight::gi {

const std::vector<MethodInfo>& registeredMethods() {
  static const std::vector<MethodInfo> methods = [] {
    auto spp = [](GiSettings& g, int q) {
      g.samplesPerPixel = q;
      g.targetRelativeError = 0;
      g.timeLimitSeconds = 0;
    };
    std::vector<MethodInfo> m;
    m.push_back({"reference",
                 "path-traced ground truth (Embree, CPU): all bounces",
                 false,
                 "samples per pixel",
                 {1, 4, 16, 64},
                 spp,
                 createReferenceMethod,
                 {}});
    m.push_back({"direct",
                 "the reference's path tracer stopped after one bounce: direct light (CPU)",
                 false,
                 "samples per pixel",
                 {1, 4, 16, 64},
                 spp,
                 createDirectMethod,
                 {}});
    m.push_back({"raster",
                 "real-time direct light through the GI frame: G-buffer, shadow maps (GL)",
                 true,
                 "shadow-map texels",
                 {256, 512, 1024, 2048},
                 [](GiSettings& g, int q) {
                   if (!g.parameters.is_object()) g.parameters = nlohmann::json::object();
                   g.parameters["shadow_map_size"] = q;
                 },
                 [](const Scene& s, const MethodContext& c) { return createRasterMethod(s, c); },
                 {}});
    m.push_back(
        {"vpl",
         "real-time GI: importance-warped VPLs with imperfect shadow maps on the resident cut (GL)",
         true,
         "VPLs",
         {64, 256, 1024, 4096},
         [](GiSettings& g, int q) {
           if (!g.parameters.is_object()) g.parameters = nlohmann::json::object();
           g.parameters["vpls"] = q;
         },
         createVplMethod,
         {{"1 bounce", [](GiSettings& g) { g.maxBounces = 1; }},
          {"2 bounces", [](GiSettings& g) { g.maxBounces = 2; }},
          {"3 bounces", [](GiSettings& g) { g.maxBounces = 3; }},
          {"exact visibility", [](GiSettings& g) { g.parameters["visibility"] = "exact"; }}}});
    m.push_back(
        {"pbgi",
         "real-time GI: point-based GI on a bounding-sphere hierarchy of the resident cut (GL)",
         true,
         "micro-buffer m-pixels per side",
         {8, 16, 32},
         [](GiSettings& g, int q) {
           if (!g.parameters.is_object()) g.parameters = nlohmann::json::object();
           g.parameters["micro_buffer"] = q;
         },
         createPbgiMethod,
         {{"classic", [](GiSettings& g) { g.parameters["variant"] = "classic"; }},
          {"mip", [](GiSettings& g) { g.parameters["variant"] = "mip"; }},
          {"no pruning", [](GiSettings& g) { g.parameters["prune"] = false; }},
          {"conservative", [](GiSettings& g) { g.parameters["conservative"] = true; }},
          {"no meshes", [](GiSettings& g) { g.parameters["meshes"] = false; }}}});
    // Samples per pixel: MIS and the baselines split them between the BSDF and the environment
    // (the paper's half each), BIS resamples them (at most 64) from 20 times as many proposals
    // (the paper's 400 for 20), SMC carries them (at most 32) with the paper's 3 intermediate
    // distributions.
    m.push_back(
        {"ibl",
         "real-time image-based lighting from HDR environment maps and video light probes: MIS, "
         "BIS, SMC (GL)",
         true,
         "samples per pixel",
         {2, 8, 32},
         [](GiSettings& g, int q) {
           if (!g.parameters.is_object()) g.parameters = nlohmann::json::object();
           const std::string e = g.parameters.value("estimator", std::string("mis"));
           if (e == "bis") {
             g.parameters["bis_samples"] = std::min(q, 64);
             g.parameters["bis_proposals"] = 20 * q;
           } else if (e == "smc") {
             g.parameters["smc_particles"] = std::min(q, 32);
           } else {
             g.parameters["brdf_samples"] = e == "env" ? 0 : e == "brdf" ? q : (q + 1) / 2;
             g.parameters["env_samples"] = e == "env" ? q : e == "brdf" ? 0 : q / 2;
           }
         },
         createIblMethod,
         {{"bis", [](GiSettings& g) { g.parameters["estimator"] = "bis"; }},
          {"smc", [](GiSettings& g) { g.parameters["estimator"] = "smc"; }},
          {"environment sampling", [](GiSettings& g) { g.parameters["estimator"] = "env"; }},
          {"bsdf sampling", [](GiSettings& g) { g.parameters["estimator"] = "brdf"; }}}});
    return m;
  }();
  return methods;
}

const MethodInfo* findMethod(const std::string& name) {
  for (const auto& m : registeredMethods())
    if (m.name == name) return &m;
  return nullptr;
}

std::string methodList() {
  std::string s;
  for (const auto& m : registeredMethods()) s += (s.empty() ? "" : ", ") + m.name;
  return s;
}

std::unique_ptr<Method> createMethod(const Scene& scene, const MethodContext& ctx) {
  const MethodInfo* m = findMethod(scene.gi.method);
  if (!m)
    throw Error(scene.file.string(), "gi.method",
                "unknown method '" + scene.gi.method + "' (" + methodList() + ")");
  return m->create(scene, ctx);
}

}  // namespace nestlight::gi
