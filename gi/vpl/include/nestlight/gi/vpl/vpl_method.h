// `vpl`: real-time global illumination with virtual point lights and imperfect shadow maps on
// the resident cut (Preiner, "Real-Time Global Illumination in Point Clouds"; ISMs after Ritschel
// et al. 2008; sample warping after Clarberg et al. 2005). Built on the raster frame: the camera's
// G-buffer, shadow maps and direct light are raster's; this method adds the light G-buffer, the
// importance-warped VPLs and their further generations, the ISM atlas with pull-push, interleaved
// shading and the geometry-aware filter. docs/SCENE.md describes the parameters.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <string>
#include <vector>

#include "nestlight/gi/method.h"
#include "nestlight/gi/method_info.h"
#include "nestlight/gi/method_parameters.h"
#include "nestlight/gi/scene.h"

namespace nestlight::gi {

struct VplParameters {
  int count = 1024;  // VPLs per generation ("vpls")
  // "vpls": "auto": the count is picked to fit target_ms per frame (stills: from two probe frames
  // fitted as a + b x count; interactive: halved or doubled when the frame time leaves
  // [0.5, 1.25] x target), a power of two from 16 to the most the ISM atlas holds.
  bool autoCount = false;
  double targetMs = 33;
  int lightResolution = 256;    // light G-buffer texels per side and layer (a power of two)
  int ismSize = 32;             // texels per side of one ISM (a power of two)
  int ismPoints = 2048;         // points one ISM splats at most
  int pullPushLevels = 3;       // pull-push levels (0: none)
  int interleave = 4;           // n: n x n VPL subsets
  float clampFraction = 0.02f;  // clamp distance, as a fraction of the scene's bounding radius
  float ismBias = 1.5f;         // ISM depth bias, in texel footprints (slope-scaled)
  float lodScale = 1.0f;        // ISM points' spacing, in texel footprints
  double energyStop = 0.01;     // stop bouncing when a generation re-emits less than this fraction
  // "ism" (the method), "none" (every VPL sees everything: what visibility costs), "exact"
  // (Embree rays on the CPU, per pixel and VPL of its subset: separates the ISMs' error from the
  // VPLs'; the frame then also counts how often the ISMs agreed).
  enum class Visibility { Ism, None, Exact } visibility = Visibility::Ism;
};

// The gi.parameters vpl reads beside raster's (src/vpl_parameters.cpp), and its entry in the
// registry.
const ParameterSpecs& vplParameterSpecs();
MethodInfo vplMethodInfo();
// From scene.gi.parameters; throws nestlight::Error naming the file and
// scene.gi.parameters.<key>.
VplParameters vplParameters(const Scene& scene);

std::unique_ptr<Method> createVplMethod(const Scene& scene, const MethodContext& ctx);

// The warping stage alone, for tests: `importance` holds `layers` layers of size x size texels
// (size a power of two); returns `count` samples (texel x, y, layer; the texel's probability;
// invalid when nothing had importance). Needs a current GL context.
struct WarpedSample {
  int x = 0, y = 0, layer = 0;
  bool valid = false;
  float probability = 0;
};
std::vector<WarpedSample> warpImportanceOnGpu(const std::vector<float>& importance, int size,
                                              int layers, int count);

}  // namespace nestlight::gi
