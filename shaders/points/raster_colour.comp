#include "raster_common.glsl"

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uNumPoints) return;
  uint pixel;
  float d;
  if (!projectPoint(i, pixel, d)) return;
  if (d > uintBitsToFloat(fb.depth[pixel]) * 1.01) return;
  uvec3 c8 = colourWordToSum(pointColour(i));
  atomicAdd(acc.accum[4u * pixel], c8.r);
  atomicAdd(acc.accum[4u * pixel + 1u], c8.g);
  atomicAdd(acc.accum[4u * pixel + 2u], c8.b);
  atomicAdd(acc.accum[4u * pixel + 3u], 1u);
  // Any of the nearest points' normals will do; a plain store races benignly.
  nb.normal[pixel] = pointNormalWord(i);
}
