// The GI frame's interface for C++: shaders/interface/frame_interface.glsl, the one file GLSL
// and C++ share, read with the glm types standing in for GLSL's.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>

namespace nestlight::frame {

namespace glsl {
using vec4 = glm::vec4;
using ivec4 = glm::ivec4;
using mat4 = glm::mat4;
#include "interface/frame_interface.glsl"
}  // namespace glsl

using FrameBlock = glsl::FrameBlock;
using LightRecord = glsl::LightRecord;
using MaterialRecord = glsl::MaterialRecord;
using ClipVolumeRecord = glsl::ClipVolumeRecord;
using ClipBlock = glsl::ClipBlock;
static_assert(sizeof(FrameBlock) == 4 * 64 + 4 * 16, "FrameBlock must keep std140's layout");
static_assert(sizeof(LightRecord) == 5 * 16, "LightRecord must keep std430's layout");
static_assert(sizeof(MaterialRecord) == 4 * 16, "MaterialRecord must keep std430's layout");
static_assert(sizeof(ClipVolumeRecord) == 64 + 2 * 16,
              "ClipVolumeRecord must keep std140's layout");
static_assert(sizeof(ClipBlock) == 16 + NL_MAX_CLIP_VOLUMES * sizeof(ClipVolumeRecord) +
                                       NL_MAX_CLIP_VERTICES / 2 * 16,
              "ClipBlock must keep std140's layout");

inline constexpr size_t kGpuPointBytes = NL_POINT_WORDS * 4;

}  // namespace nestlight::frame
