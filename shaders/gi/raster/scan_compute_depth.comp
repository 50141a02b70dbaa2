// Pass 1 of the GI frame's compute rasteriser (scan_compute_common.glsl): nearest depth per pixel.
#include "scan_compute_common.glsl"
void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uNumPoints) return;
  uint pixel;
  float d;
  if (projectPoint(i, pixel, d)) atomicMin(sd.depth[pixel], floatBitsToUint(d));
}
