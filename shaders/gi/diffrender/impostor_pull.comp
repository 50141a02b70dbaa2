// The first half of the distance impostor's hole filling (after Marroquim, Kraus and Cavalcanti,
// "Efficient Point-Based Rendering Using Image Reconstruction", 2007, as the ISMs' pull-push):
// each face's texels as coverage-weighted sums, (rgb w, w) and (distance w), whose mips (box
// averages, made by the driver) are then each region's covered mean and its coverage.
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0) uniform sampler2DArray uRaw;  // rgb radiance, a distance (0: no splat)
layout(rgba32f, binding = 0) uniform writeonly image2DArray uColourSum;
layout(r32f, binding = 1) uniform writeonly image2DArray uDistanceSum;
uniform int uSize;

void main() {
  ivec3 p = ivec3(gl_GlobalInvocationID.xyz);
  if (p.x >= uSize || p.y >= uSize) return;
  vec4 v = texelFetch(uRaw, p, 0);
  float w = v.a > 0.0 ? 1.0 : 0.0;
  imageStore(uColourSum, p, vec4(v.rgb * w, w));
  imageStore(uDistanceSum, p, vec4(v.a * w));
}
