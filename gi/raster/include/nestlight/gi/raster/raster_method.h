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

#include "nestlight/gi/frame/frame_parameters.h"
#include "nestlight/gi/method.h"
#include "nestlight/gi/method_info.h"
#include "nestlight/gi/method_parameters.h"

namespace nestlight::gi {

// raster's entry in the registry (src/raster_parameters.cpp).
MethodInfo rasterMethodInfo();

// From the scene's gi.parameters (rasterParameterSpecs()); throws nestlight::Error naming the
// scene file and the field.
FrameParameters rasterParameters(const Scene& scene);

// Opens the scene's scans and meshes and, unless ctx says one is current, a headless GL context.
std::unique_ptr<Method> createRasterMethod(const Scene& scene, const MethodContext& ctx);

}  // namespace nestlight::gi
