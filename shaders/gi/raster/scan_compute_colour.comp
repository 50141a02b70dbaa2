// Pass 2 of the GI frame's compute rasteriser: the points within 1% of the nearest depth add their
// colour; one of them leaves its normal and its splat radius (the finest drawn node's spacing,
// for shadow offsets); plain stores race benignly, any of the nearest points will do.
#include "scan_compute_common.glsl"
uniform float uSizeScale;
void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uNumPoints) return;
  uint pixel;
  float d;
  if (!projectPoint(i, pixel, d)) return;
  if (d > uintBitsToFloat(sd.depth[pixel]) * 1.01) return;
  uvec3 c8 = colourWordToSum(pointColour(i));
  atomicAdd(sa.accum[4u * pixel], c8.r);
  atomicAdd(sa.accum[4u * pixel + 1u], c8.g);
  atomicAdd(sa.accum[4u * pixel + 2u], c8.b);
  atomicAdd(sa.accum[4u * pixel + 3u], 1u);
  sn.normal[pixel] = pointNormalWord(i);
  sr.radius[pixel] = 0.5 * finestSpacing(pointLocal(i)) * uSizeScale;
}
