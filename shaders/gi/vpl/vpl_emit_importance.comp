// Radiance-cache mode: the scan's points emit their colour (Preiner's VPLs drawn on the emitting
// points, so the scan lights the inserted objects). Each pool point's importance is what it emits,
// luminance x area, laid out row by row over a square level 0 of the sum pyramid that
// vpl_warp.comp descends.
#include "../../interface/frame_interface.glsl"
#include "vpl_interface.glsl"
#include "../common/brdf.glsl"
layout(local_size_x = 128) in;
layout(std430, binding = VPL_SSBO_POOL) readonly buffer Pool { PoolPoint pool[]; };
layout(std430, binding = VPL_SSBO_PYRAMID) buffer Pyramid { float pyramid[]; };
uniform int uScanPoints;  // the pool's first points are the scans'
void main() {
  int i = int(gl_GlobalInvocationID.x);
  if (i >= uScanPoints) return;
  PoolPoint q = pool[i];
  vec3 c = vec3(unpackHalf2x16(q.surface.y), unpackHalf2x16(q.surface.z & 0xffffu).x);
  float imp = luminance(c) * uintBitsToFloat(q.surface.w);
  pyramid[i] = isinf(imp) || isnan(imp) || imp < 0.0 ? 0.0 : imp;
}
