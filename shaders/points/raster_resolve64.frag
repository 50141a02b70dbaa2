// Resolve of the 64-bit compute rasteriser: the nearest point's colour and depth per pixel.
#extension GL_ARB_gpu_shader_int64 : require

layout(std430, binding = 4) readonly buffer Packed { uint64_t packed[]; } fb64;

uniform ivec2 uViewport;
uniform mat4 uClipFromView;

layout(location = 0) out vec4 outColour;
layout(location = 1) out vec4 outNormal;

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  uint64_t v = fb64.packed[uint(p.y * uViewport.x + p.x)];
  if (v == 0xffffffffffffffffUL) discard;
  outColour = vec4(unpackUnorm4x8(uint(v & 0xffffffffUL)).rgb, 1.0);
  outNormal = vec4(0.0);  // this variant keeps colour only; GI passes take normals from the points path
  float d = uintBitsToFloat(uint(v >> 32));
  vec4 clip = uClipFromView * vec4(0.0, 0.0, -d, 1.0);
  gl_FragDepth = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
}
