// Pass 3 of the GI frame's compute rasteriser: the averaged colour (linear, times the scan's colour
// scale), the normal and the nearest depth into the G-buffer; the depth test
// against the meshes already there keeps whichever is nearer.
#include "../common/gbuffer_out.glsl"
#include "../../common/colour_word.glsl"
#include "../../common/octahedral.glsl"
layout(std430, binding = NL_SSBO_SCAN_DEPTH) readonly buffer ScanDepth { uint depth[]; } sd;
layout(std430, binding = NL_SSBO_SCAN_ACCUM) readonly buffer ScanAccum { uint accum[]; } sa;
layout(std430, binding = NL_SSBO_SCAN_NORMAL) readonly buffer ScanNormal { uint normal[]; } sn;
layout(std430, binding = NL_SSBO_SCAN_RADIUS) readonly buffer ScanRadius { float radius[]; } sr;
uniform ivec2 uViewport;
uniform mat4 uClipFromView;      // the tile's
uniform float uColourScale;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  uint pixel = uint(p.y * uViewport.x + p.x);
  uint count = sa.accum[4u * pixel + 3u];
  if (count == 0u) discard;
  vec3 c = colourSumToLinear(vec3(sa.accum[4u * pixel], sa.accum[4u * pixel + 1u], sa.accum[4u * pixel + 2u]), float(count));
  float d = uintBitsToFloat(sd.depth[pixel]);
  vec4 clip = uClipFromView * vec4(0.0, 0.0, -d, 1.0);
  gl_FragDepth = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
  writeGBuffer(c * uColourScale, sr.radius[pixel], decodeNormal(sn.normal[pixel]), NL_MATERIAL_LAMBERT,
               NL_SOURCE_SCAN, 1.0, 0.0, uint(NL_NO_MATERIAL));
}
