// Compute rasteriser, the one-pass 64-bit variant of Schütz, Kerbl, Wimmer 2021 for GPUs with
// 64-bit atomics: each pixel keeps min((depth bits << 32) | colour), so the nearest point's
// colour wins in one atomicMin, and likewise min((depth bits << 32) | normal) in a second buffer,
// so the G-buffer gets the nearest point's normal too (the GI passes shade with it). Compiled only
// where GL_NV_shader_atomic_int64 exists.
#extension GL_ARB_gpu_shader_int64 : require
#extension GL_NV_shader_atomic_int64 : require

#include "../common/point_data.glsl"
#include "../common/clip_volumes.glsl"

layout(local_size_x = 128) in;

layout(std430, binding = NL_SSBO_RASTER_PACKED) buffer Packed { uint64_t words[]; } fb64;
layout(std430, binding = NL_SSBO_RASTER_PACKED_NORMAL) buffer PackedNormals { uint64_t words[]; } nb64;

uniform ivec2 uViewport;

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uNumPoints || !clipKeeps(pointCamRel(i))) return;
  vec4 view = uViewFromCamRel * vec4(pointCamRel(i), 1.0);
  vec4 clip = uClipFromView * view;
  if (clip.w <= 0.0) return;
  vec3 ndc = clip.xyz / clip.w;
  if (any(lessThan(ndc, vec3(-1.0))) || any(greaterThanEqual(ndc, vec3(1.0)))) return;
  ivec2 p = clamp(ivec2((ndc.xy * 0.5 + 0.5) * vec2(uViewport)), ivec2(0), uViewport - 1);
  uint pixel = uint(p.y * uViewport.x + p.x);
  uint64_t depthBits = uint64_t(floatBitsToUint(-view.z)) << 32;
  atomicMin(fb64.words[pixel], depthBits | uint64_t(pointColour(i)));
  atomicMin(nb64.words[pixel], depthBits | uint64_t(pointNormalWord(i)));
}
