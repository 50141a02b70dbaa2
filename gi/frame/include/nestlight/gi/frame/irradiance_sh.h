// The environment's irradiance on diffuse lobes as order-2 spherical harmonics (Ramamoorthi and
// Hanrahan 2001, "An Efficient Representation for Irradiance Environment Maps"): what the GI
// frame's direct light adds for the sky, unshadowed.
#pragma once

#include <array>
#include <glm/glm.hpp>

#include "nestlight/gi/environment_map.h"

namespace nestlight::gi {

// The nine coefficients L_lm of `env` (its rotation and scale applied), each times the cosine
// lobe's A_l and its basis constant, in the order shaders/gi/raster/direct_light.frag evaluates
// them.
std::array<glm::vec3, 9> irradianceSh(const EnvironmentMap& env);

}  // namespace nestlight::gi
