// Pass 3 of the compute rasteriser: average colour and nearest depth into the G-buffer.
#include "../interface/frame_interface.glsl"
layout(std430, binding = NL_SSBO_RASTER_DEPTH) readonly buffer Depth { uint depth[]; } fb;
layout(std430, binding = NL_SSBO_RASTER_ACCUM) readonly buffer Accum { uint accum[]; } acc;
layout(std430, binding = NL_SSBO_RASTER_NORMAL) readonly buffer Normals { uint normal[]; } nb;

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
  uint count = acc.accum[4u * pixel + 3u];
  if (count == 0u) discard;
  outColour = vec4(colourSumToLinear(vec3(acc.accum[4u * pixel], acc.accum[4u * pixel + 1u], acc.accum[4u * pixel + 2u]),
                                     float(count)), 1.0);
  vec3 n = mat3(uViewFromCamRel) * decodeNormal(nb.normal[pixel]);
  outNormal = vec4(n, dot(n, n) > 0.0 ? 1.0 : 0.0);
  float d = uintBitsToFloat(fb.depth[pixel]);
  vec4 clip = uClipFromView * vec4(0.0, 0.0, -d, 1.0);
  gl_FragDepth = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
}
