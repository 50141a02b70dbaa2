// `ibl`'s declaration: its parameters, how `bench gi`'s samples per pixel split between its
// estimators, and its entry in the registry.
#include <algorithm>

#include "nestlight/gi/frame/frame_parameters.h"
#include "nestlight/gi/ibl/ibl_method.h"
#include "nestlight/gi/method_info.h"
#include "nestlight/octree/json_field.h"

namespace nestlight::gi {

namespace {

// BIS: N at most (ibl_shade.comp's IBL_PICKS_MAX); SMC: N at most (the paper: 1 to 32).
constexpr int kSmcMax = 32, kBisMax = 64;

// Samples per pixel: MIS and the baselines split them between the BSDF and the environment (the
// paper's half each), BIS resamples them (at most 64) from 20 times as many proposals (the
// paper's 400 for 20), SMC carries them (at most 32) with the paper's 3 intermediate
// distributions.
void applyIblQuality(GiSettings& g, int q) {
  if (!g.parameters.is_object()) g.parameters = nlohmann::json::object();
  const std::string e = g.parameters.value("estimator", std::string("mis"));
  if (e == "bis") {
    g.parameters["bis_samples"] = std::min(q, kBisMax);
    g.parameters["bis_proposals"] = 20 * q;
  } else if (e == "smc") {
    g.parameters["smc_particles"] = std::min(q, kSmcMax);
  } else {
    g.parameters["brdf_samples"] = e == "env" ? 0 : e == "brdf" ? q : (q + 1) / 2;
    g.parameters["env_samples"] = e == "env" ? q : e == "brdf" ? 0 : q / 2;
  }
}

}  // namespace

const ParameterSpecs& iblParameterSpecs() {
  using P = ParameterSpec;
  static const ParameterSpecs specs = {
      P::choice("estimator", {"mis", "bis", "smc", "env", "brdf"}, "mis",
                "mis (default), bis, smc, or the baselines env (environment sampling alone) and "
                "brdf (docs/IBL.md)")
          .asFlag(),
      P::integer("brdf_samples", 0, 4096, 15, "MIS: BSDF samples per pixel (the paper: 15)"),
      P::integer("env_samples", 0, 4096, 15, "MIS: environment samples per pixel (the paper: 15)"),
      P::integer("bis_proposals", 1, 65536, 400,
                 "BIS (and SMC's initialisation): BSDF proposals per pixel (the paper: 400)"),
      P::integer("bis_samples", 1, kBisMax, 20,
                 "BIS: samples resampled from the proposals (the paper: 20)"),
      P::integer("smc_particles", 1, kSmcMax, 8,
                 "SMC: samples per pixel carried between frames (the paper: 8)"),
      P::integer("smc_intermediate", 1, 16, 3,
                 "SMC: intermediate distributions per frame (the paper: 3)"),
      P::number("smc_local_probability", 0, 1, 0.5,
                "SMC: the share of local Metropolis-Hastings moves"),
      P::number("smc_local_degrees", 0.01, 90, 3, "SMC: a local move's largest angle"),
      P::number("smc_reinit_ratio", 1, 1e30, 4,
                "SMC: reinitialise where Z_t / Z_t-1 exceeds this (docs/IBL.md)"),
      P::boolean("visibility", true, "trace visibility against the meshes (false: unshadowed)"),
      P::boolean("smc_statistics", false,
                 "SMC: report the normalising constants' mean and median per frame"),
      P::boolean("smc_reinit_on_drop", false,
                 "SMC: also reinitialise where Z_t / Z_t-1 falls below 1 / smc_reinit_ratio"),
      P::integer("smc_band_rows", 0, 1 << 16, 0,
                 "SMC: image rows shaded per dispatch (0: as many as the state's buffers allow)"),
  };
  return specs;
}

IblParameters iblParameters(const Scene& scene) {
  const ResolvedParameters r = resolveParameterValues(scene, iblParameterSpecs());
  IblParameters p;
  const std::string e = r.string("estimator");
  p.estimator = e == "mis"   ? IblParameters::Estimator::Mis
                : e == "bis" ? IblParameters::Estimator::Bis
                : e == "smc" ? IblParameters::Estimator::Smc
                : e == "env" ? IblParameters::Estimator::Environment
                             : IblParameters::Estimator::Brdf;
  p.brdfSamples = int(r.integer("brdf_samples"));
  p.envSamples = int(r.integer("env_samples"));
  p.bisProposals = int(r.integer("bis_proposals"));
  p.bisSamples = int(r.integer("bis_samples"));
  p.smcParticles = int(r.integer("smc_particles"));
  p.smcIntermediate = int(r.integer("smc_intermediate"));
  p.smcLocalProbability = float(r.number("smc_local_probability"));
  p.smcLocalDegrees = float(r.number("smc_local_degrees"));
  p.smcReinitRatio = float(r.number("smc_reinit_ratio"));
  p.visibility = r.boolean("visibility");
  p.smcStatistics = r.boolean("smc_statistics");
  p.smcReinitOnDrop = r.boolean("smc_reinit_on_drop");
  p.smcBandRows = int(r.integer("smc_band_rows"));
  const JsonField f(scene.gi.parameters, "scene.gi.parameters", scene.file.string());
  if (p.estimator == IblParameters::Estimator::Mis && p.brdfSamples + p.envSamples == 0)
    f.fail("MIS needs at least one sample: brdf_samples + env_samples > 0");
  if (p.estimator == IblParameters::Estimator::Environment && p.envSamples == 0)
    f.fail("estimator \"env\" samples the environment alone: env_samples must be positive");
  if (p.estimator == IblParameters::Estimator::Brdf && p.brdfSamples == 0)
    f.fail("estimator \"brdf\" samples the BSDF alone: brdf_samples must be positive");
  return p;
}

MethodInfo iblMethodInfo() {
  MethodInfo m;
  m.name = "ibl";
  m.summary =
      "real-time image-based lighting from HDR environment maps and video light probes: MIS, "
      "BIS, SMC (GL)";
  m.gpu = true;
  m.qualityName = "samples per pixel";
  m.defaultQualities = {2, 8, 32};
  m.applyQuality = applyIblQuality;
  m.create = createIblMethod;
  // Its light is the environment's; the scene's lights are the raster frame's direct light.
  m.whyNotApplicable = [](const Scene& s) -> std::string {
    return s.environment ? ""
                         : "the scene has no environment, and ibl's own light is the "
                           "environment's: it would render raster's direct light alone";
  };
  m.variants = {{"bis", [](GiSettings& g) { g.parameters["estimator"] = "bis"; }},
                {"smc", [](GiSettings& g) { g.parameters["estimator"] = "smc"; }},
                {"environment sampling", [](GiSettings& g) { g.parameters["estimator"] = "env"; }},
                {"bsdf sampling", [](GiSettings& g) { g.parameters["estimator"] = "brdf"; }}};
  m.parameters = rasterParameterSpecs();
  m.parameters.insert(m.parameters.end(), iblParameterSpecs().begin(), iblParameterSpecs().end());
  return m;
}

}  // namespace nestlight::gi
