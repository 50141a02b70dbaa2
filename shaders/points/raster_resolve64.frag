// Resolve of the 64-bit compute rasteriser: the nearest point's colour and depth per pixel.
#extension GL_ARB_gpu_shader_int64 : require

#include "../interface/frame_interface.glsl"
layout(std430, binding = NL_SSBO_RASTER_PACKED) readonly buffer Packed { uint64_t words[]; } fb64;
layout(std430, binding = NL_SSBO_RASTER_PACKED_NORMAL) readonly buffer PackedNormals { uint64_t words[]; } nb64;

#include "../common/octahedral.glsl"
#include "../common/colour_word.glsl"

uniform ivec2 uViewport;
uniform mat4 uClipFromView;
uniform mat4 uViewFromCamRel;

layout(location = 0) out vec4 outColour;
layout(location = 1) out vec4 outNormal;

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  uint pixel = uint(p.y * uViewport.x + p.x);
  uint64_t v = fb64.words[pixel];
  if (v == 0xffffffffffffffffUL) discard;
  outColour = vec4(colourWordLinear(uint(v & 0xffffffffUL)), 1.0);
  // The nearest point's normal (ties at equal depth: the smaller code, a point at that depth too).
  vec3 n = mat3(uViewFromCamRel) * decodeNormal(uint(nb64.words[pixel] & 0xffffffffUL));
  outNormal = vec4(n, dot(n, n) > 0.0 ? 1.0 : 0.0);
  float d = uintBitsToFloat(uint(v >> 32));
  vec4 clip = uClipFromView * vec4(0.0, 0.0, -d, 1.0);
  gl_FragDepth = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
}
