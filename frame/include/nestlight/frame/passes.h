// Passes every method's frame can use.
#pragma once

#include <memory>
#include <string>

#include "nestlight/frame/frame_graph.h"

namespace nestlight::frame {

// Linear HDR `input` (a tile target) -> display-referred `output` (RGBA8): gi/metrics' tone map
// (2^exposureStops, clamp, sRGB), NaN as magenta. `exposureStops` is read at every run.
void addToneMapPass(FrameGraph& graph, const std::string& input, const std::string& output,
                    std::shared_ptr<const float> exposureStops,
                    const std::string& name = "tone_map");

// Clears the bound framebuffer as an empty G-buffer (shaders/interface/frame_interface.glsl):
// depth 1, base colour and normal 0 (no normal), material "none" (NL_NO_MATERIAL).
void clearGBuffer();

}  // namespace nestlight::frame
