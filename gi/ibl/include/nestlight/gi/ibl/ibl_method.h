// `ibl`: image-based lighting of the scene from its HDR environment map or video light probe, in
// real time on the GI frame: the estimators of Kronander, Dahlin, Jönsson, Kok, Schön and Unger,
// "Real-time video based lighting using GPU raytracing" (2014): multiple importance sampling
// (section 4), bidirectional importance sampling (section 5) and the sequential Monte Carlo
// sampler (section 6), with visibility by rays (shaders/gi/ibl/). Direct light of the scene's
// lights comes from the raster frame. docs/IBL.md describes the parameters and deviations.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "nestlight/gi/method.h"
#include "nestlight/gi/method_info.h"
#include "nestlight/gi/method_parameters.h"
#include "nestlight/gi/scene.h"

namespace nestlight::gi {

struct IblParameters {
  // mis | bis | smc, and the benchmark's baselines: environment-map sampling alone ("env", with
  // env_samples samples) and BSDF sampling alone ("brdf", with brdf_samples).
  enum class Estimator { Mis, Bis, Smc, Environment, Brdf } estimator = Estimator::Mis;
  int brdfSamples = 15;    // MIS: N_rho (the paper's Fig. 3: 15 and 15)
  int envSamples = 15;     // MIS: N_L
  int bisProposals = 400;  // BIS (and SMC's initialisation): M BSDF proposals (the paper: 400)...
  int bisSamples = 20;     // ...resampled to N (the paper: 20; at most 64)
  int smcParticles = 8;  // SMC: N samples per pixel carried between frames (the paper: 8; 1 to 32)
  int smcIntermediate = 3;           // SMC: intermediate distributions per frame (the paper: 3)
  float smcLocalProbability = 0.5f;  // SMC: nu, the share of local Metropolis-Hastings moves
  float smcLocalDegrees = 3;         // SMC: a local move's largest angle ("a few degrees")
  float smcReinitRatio = 4;          // SMC: reinitialise where Z_t / Z_t-1 exceeds this...
  bool smcReinitOnDrop = false;      // ...or falls below its inverse (docs/IBL.md)
  bool visibility = true;            // trace V(w) against the meshes (false: unshadowed)
  // SMC: read the per-pixel normalising constants back after each frame and report their mean
  // and median (attributes nestlight:ibl_smc_z_*; tests and the benchmark's Z tracking).
  bool smcStatistics = false;
  // SMC: image rows shaded per dispatch (0: as many as the state's 128 MiB buffer ranges allow);
  // a band reads the previous frame's state of the rows about it. For tests of the banding.
  int smcBandRows = 0;
};

// The gi.parameters ibl reads beside raster's (src/ibl_parameters.cpp), and its entry in the
// registry.
const ParameterSpecs& iblParameterSpecs();
MethodInfo iblMethodInfo();
// From scene.gi.parameters; throws nestlight::Error naming scene.gi.parameters.<key>.
IblParameters iblParameters(const Scene& scene);
const char* estimatorName(IblParameters::Estimator e);

std::unique_ptr<Method> createIblMethod(const Scene& scene, const MethodContext& ctx);

}  // namespace nestlight::gi
