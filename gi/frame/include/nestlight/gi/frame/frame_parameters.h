// The GI frame's parameters (a scene's gi.parameters that `raster` and every method on its frame
// read): shadow-map size, the scans' rasteriser and splatting, streaming budgets, tiling.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "nestlight/gi/method_parameters.h"
#include "nestlight/gi/scene.h"

namespace nestlight::gi {

struct FrameParameters {
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

// The gi.parameters the frame reads (src/frame_parameters.cpp).
const ParameterSpecs& rasterParameterSpecs();

// From the scene's gi.parameters (rasterParameterSpecs()), accepting `otherKeys` too (a method
// built on the frame reads those); throws nestlight::Error naming the scene file and the field.
FrameParameters parseFrameParameters(const Scene& scene, const std::vector<std::string>& otherKeys);

}  // namespace nestlight::gi
