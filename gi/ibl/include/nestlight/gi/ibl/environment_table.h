// The environment's sampling table for the GPU, rebuilt for every frame of a video light probe:
// tabulated row (marginal) and column (conditional) CDFs, the inversion method of Kronander et
// al., "Real-time video based lighting using GPU raytracing" (2014), section 7, after pbrt. The
// densities are EnvironmentMap's (gi/core): texel weight luminance x solid angle, cos theta
// uniform inside a row, so the GPU's pdf per solid angle is luminance / power in every texel, the
// CPU's exactly. Layout: shaders/gi/ibl/ibl_interface.glsl (IBL_ENV_*).
#pragma once

#include <vector>

#include "nestlight/frame/interface.h"
#include "nestlight/gi/environment_map.h"

// The table's layout and the method's slots (IBL_ENV_*, IBL_SSBO_*): macros only.
#include "gi/ibl/ibl_interface.glsl"

namespace nestlight::gi::ibl {

struct EnvironmentTable {
  std::vector<float> data;
  double buildSeconds = 0;
  bool black = true;
};

EnvironmentTable buildEnvironmentTable(const EnvironmentMap& map);

}  // namespace nestlight::gi::ibl
