#include "raster_common.glsl"
// Pass 1 of the compute rasteriser (raster_common.glsl): nearest depth per pixel.
void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uNumPoints) return;
  uint pixel;
  float d;
  if (projectPoint(i, pixel, d)) atomicMin(fb.depth[pixel], floatBitsToUint(d));
}
