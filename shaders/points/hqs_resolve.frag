// High-quality splatting, pass 3 of 3: normalises the sums of pass 2 into the G-buffer: the
// weighted mean colour, the weighted mean normal (renormalised; none when the scan has none) and
// the weighted mean depth, which is smooth across splats (so eye-dome lighting outlines shapes
// rather than single splats).
//   0 (default)     the point view's G-buffer (colour, view-space normal);
//   NL_SCENE_FRAME 1 the GI frame's G-buffer, with the mean splat radius; the depth test keeps
//                   meshes in front.
#include "splat_frame.glsl"
layout(binding = 0) uniform sampler2D uSumColour;
layout(binding = 1) uniform sampler2D uSumNormal;
uniform mat4 uClipFromView;   // the tile's
#if NL_SCENE_FRAME
#include "../gi/common/gbuffer_out.glsl"
layout(binding = 2) uniform sampler2D uSumRadius;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 c = texelFetch(uSumColour, p, 0);
  if (!(c.a > 0.0)) discard;
  vec4 n = texelFetch(uSumNormal, p, 0);
  vec3 normal = n.xyz / c.a;
  float len = length(normal);
  vec4 clip = uClipFromView * vec4(0.0, 0.0, -n.w / c.a, 1.0);
  gl_FragDepth = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
  writeGBuffer(c.rgb / c.a, texelFetch(uSumRadius, p, 0).r / c.a, len > 1e-4 ? normal / len : vec3(0.0),
               NL_MATERIAL_LAMBERT, NL_SOURCE_SCAN, 1.0, 0.0, uint(NL_NO_MATERIAL));
}
#else
layout(location = 0) out vec4 outColour;
layout(location = 1) out vec4 outNormal;

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 c = texelFetch(uSumColour, p, 0);
  if (c.a <= 0.0) discard;
  vec4 n = texelFetch(uSumNormal, p, 0);
  outColour = vec4(c.rgb / c.a, 1.0);
  vec3 normal = n.xyz / c.a;
  float len = length(normal);
  outNormal = len > 1e-4 ? vec4(normal / len, 1.0) : vec4(0.0);
  vec4 clip = uClipFromView * vec4(0.0, 0.0, -n.w / c.a, 1.0);
  gl_FragDepth = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
}
#endif
