// The scene volume's slab from its fixed-point sums (scene_voxelize.frag): the mean radiance
// where points fell, premultiplied by the opacity, 1 there and 0 elsewhere, so that the mips (box
// averages) hold each region's covered mean times its coverage.
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
layout(r32ui, binding = 0) uniform readonly uimage3D uSumR;
layout(r32ui, binding = 1) uniform readonly uimage3D uSumG;
layout(r32ui, binding = 2) uniform readonly uimage3D uSumB;
layout(r32ui, binding = 3) uniform readonly uimage3D uCount;
layout(r11f_g11f_b10f, binding = 4) uniform writeonly image3D uRadiance;
layout(r8, binding = 5) uniform writeonly image3D uOpacity;
uniform ivec3 uDims;
uniform int uSlabFirst, uSlabDepth;
uniform float uFixedPoint;

void main() {
  ivec3 s = ivec3(gl_GlobalInvocationID);
  if (s.x >= uDims.x || s.y >= uDims.y || s.z >= uSlabDepth || s.z + uSlabFirst >= uDims.z) return;
  uint n = imageLoad(uCount, s).r;
  vec3 c = n > 0u ? vec3(imageLoad(uSumR, s).r, imageLoad(uSumG, s).r, imageLoad(uSumB, s).r) / (float(n) * uFixedPoint) : vec3(0.0);
  ivec3 v = ivec3(s.xy, s.z + uSlabFirst);
  imageStore(uRadiance, v, vec4(c, 0.0));
  imageStore(uOpacity, v, vec4(n > 0u ? 1.0 : 0.0));
}
