// Pass 2 of the compute rasteriser (raster_common.glsl): the points within 1% of the nearest
// depth add their colour; one of them leaves its normal (and, NL_SCENE_FRAME, its splat radius:
// the finest drawn node's spacing, for shadow offsets); plain stores race benignly, any of the
// nearest points will do.
#include "raster_common.glsl"
#if NL_SCENE_FRAME
#include "splat_size.glsl"
uniform float uSizeScale;
#endif

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
  nb.normal[pixel] = pointNormalWord(i);
#if NL_SCENE_FRAME
  sr.radius[pixel] = 0.5 * finestSpacing(pointLocal(i)) * uSizeScale;
#endif
}
