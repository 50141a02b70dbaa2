#include "raster_common.glsl"

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uNumPoints) return;
  uint pixel;
  float d;
  if (projectPoint(i, pixel, d)) atomicMin(fb.depth[pixel], floatBitsToUint(d));
}
