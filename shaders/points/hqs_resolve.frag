// High-quality splatting, pass 3 of 3: normalises the sums of pass 2 into the G-buffer: the
// weighted mean colour, the weighted mean normal (renormalised; none when the scan has none) and
// the weighted mean depth, which is smooth across splats, so eye-dome lighting outlines shapes
// rather than single splats.
layout(binding = 0) uniform sampler2D uAccColour;
layout(binding = 1) uniform sampler2D uAccNormal;
uniform mat4 uClipFromView;

layout(location = 0) out vec4 outColour;
layout(location = 1) out vec4 outNormal;

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 c = texelFetch(uAccColour, p, 0);
  if (c.a <= 0.0) discard;
  vec4 n = texelFetch(uAccNormal, p, 0);
  outColour = vec4(c.rgb / c.a, 1.0);
  vec3 normal = n.xyz / c.a;
  float len = length(normal);
  outNormal = len > 1e-4 ? vec4(normal / len, 1.0) : vec4(0.0);
  vec4 clip = uClipFromView * vec4(0.0, 0.0, -n.w / c.a, 1.0);
  gl_FragDepth = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
}
