#include "raster_common.glsl"

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uNumPoints) return;
  uint pixel;
  float d;
  if (!projectPoint(i, pixel, d)) return;
  if (d > uintBitsToFloat(fb.depth[pixel]) * 1.01) return;
  vec4 c = unpackUnorm4x8(pointColour(i));
  uvec3 c8 = uvec3(round(c.rgb * 255.0));
  atomicAdd(acc.accum[4u * pixel], c8.r);
  atomicAdd(acc.accum[4u * pixel + 1u], c8.g);
  atomicAdd(acc.accum[4u * pixel + 2u], c8.b);
  atomicAdd(acc.accum[4u * pixel + 3u], 1u);
  // Any of the nearest points' normals will do; a plain store races benignly.
  nb.normal[pixel] = pointNormalWord(i);
}
