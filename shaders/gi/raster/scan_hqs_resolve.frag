// High-quality splatting into the G-buffer, pass 3 of 3: the weighted means into the G-buffer
// (depth from the mean view depth, smooth across splats); the depth test keeps meshes in front.
#include "../common/gbuffer_out.glsl"
layout(binding = 0) uniform sampler2D uSumColour;
layout(binding = 1) uniform sampler2D uSumNormal;
layout(binding = 2) uniform sampler2D uSumRadius;
uniform mat4 uClipFromView;   // the tile's
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
