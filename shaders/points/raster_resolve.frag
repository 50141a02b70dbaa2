// Pass 3 of the compute rasteriser: the average colour and the nearest depth into the G-buffer.
//   0 (default)     the point view's (colour, view-space normal);
//   NL_SCENE_FRAME 1 the GI frame's: the colour times the scan's colour scale, the world normal,
//                   the splat radius; the depth test against the meshes already there keeps
//                   whichever is nearer.
#include "splat_frame.glsl"
#include "../interface/frame_interface.glsl"
// The per-pixel buffers of raster_common.glsl, read.
#if NL_SCENE_FRAME
layout(std430, binding = NL_SSBO_SCAN_DEPTH) readonly buffer Depth { uint depth[]; } fb;
layout(std430, binding = NL_SSBO_SCAN_ACCUM) readonly buffer Accum { uint accum[]; } acc;
layout(std430, binding = NL_SSBO_SCAN_NORMAL) readonly buffer Normals { uint normal[]; } nb;
layout(std430, binding = NL_SSBO_SCAN_RADIUS) readonly buffer Radius { float radius[]; } sr;
#else
layout(std430, binding = NL_SSBO_RASTER_DEPTH) readonly buffer Depth { uint depth[]; } fb;
layout(std430, binding = NL_SSBO_RASTER_ACCUM) readonly buffer Accum { uint accum[]; } acc;
layout(std430, binding = NL_SSBO_RASTER_NORMAL) readonly buffer Normals { uint normal[]; } nb;
#endif
#include "../common/octahedral.glsl"
#include "../common/colour_word.glsl"

uniform ivec2 uViewport;
uniform mat4 uClipFromView;      // the tile's

#if NL_SCENE_FRAME
#include "../gi/common/gbuffer_out.glsl"
uniform float uColourScale;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  uint pixel = uint(p.y * uViewport.x + p.x);
  uint count = acc.accum[4u * pixel + 3u];
  if (count == 0u) discard;
  vec3 c = colourSumToLinear(vec3(acc.accum[4u * pixel], acc.accum[4u * pixel + 1u], acc.accum[4u * pixel + 2u]), float(count));
  float d = uintBitsToFloat(fb.depth[pixel]);
  vec4 clip = uClipFromView * vec4(0.0, 0.0, -d, 1.0);
  gl_FragDepth = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
  writeGBuffer(c * uColourScale, sr.radius[pixel], decodeNormal(nb.normal[pixel]), NL_MATERIAL_LAMBERT,
               NL_SOURCE_SCAN, 1.0, 0.0, uint(NL_NO_MATERIAL));
}
#else
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
#endif
