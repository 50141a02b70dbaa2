// `raster`: a scene in real time through the GI frame, direct light only. Scans stream under the
// budgets and are drawn as splats sized by their measured spacing, meshes as triangles, both into
// the linear HDR G-buffer; every light renders a shadow map of the meshes and of the lights' cut
// (the whole scan at about a shadow map's resolution, streamed beside the camera's)
// (spot: one perspective view; point: six; directional: one orthographic view over what the
// camera sees and what casts into it, shadow_fit.h) once per frame; a deferred pass shades each
// pixel with gi/core's BSDFs. The frame every GI method builds on, and the real-time counterpart
// of the reference's `direct`.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "nestlight/gi/method.h"
#include "nestlight/gi/method_info.h"
#include "nestlight/gi/method_parameters.h"

namespace nestlight::gi {

struct RasterParameters {
  int shadowMapSize = 2048;  // texels per side of each shadow-map layer
  // The scans' G-buffer: GL_POINTS splats sized by the measured spacing, or the compute
  // rasteriser (one pixel per point, the points within 1% of the nearest depth averaged). Shadow
  // maps always take splats: a light's view needs closed surfaces.
  bool computeRasteriser = false;
  // GL_POINTS splats into the G-buffer: high-quality splatting (the kernel-weighted mean of the
  // splats within a splat radius of the front surface, Botsch et al. 2005) or basic (the nearest
  // splat wins). HQS averages a pixel's points as the reference's discs average its area.
  bool hqs = true;
  float hqsDepthEpsilon = 1.0f;       // blend splats within this many splat radii of the front
  float splatScale = 2.25f;           // splat diameter in measured spacings (the viewer's default)
  int maxTile = 2048;                 // larger images render in tiles
  uint64_t pointBudget = 5'000'000;   // points of each scan's resident cut
  uint64_t gpuBytes = 1ull << 30;     // resident bytes of each scan
  double streamTimeoutSeconds = 300;  // waiting for a view's cut to load completely
};

// The gi.parameters raster reads (src/raster_parameters.cpp), and its entry in the registry.
const ParameterSpecs& rasterParameterSpecs();
MethodInfo rasterMethodInfo();

// From the scene's gi.parameters (rasterParameterSpecs()); throws nestlight::Error naming the
// scene file and the field.
RasterParameters rasterParameters(const Scene& scene);
// The same, accepting `otherKeys` too (a method built on the raster frame reads those).
RasterParameters parseRasterParameters(const Scene& scene,
                                       const std::vector<std::string>& otherKeys);

// Opens the scene's scans and meshes and, unless ctx says one is current, a headless GL context.
std::unique_ptr<Method> createRasterMethod(const Scene& scene, const MethodContext& ctx);

}  // namespace nestlight::gi
