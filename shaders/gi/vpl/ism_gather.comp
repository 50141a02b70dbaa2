// One node of the lights' cut into the ISM point pool: world positions, normals, linear colours,
// and the area each point stands for: the square of the measured spacing of the finest node of
// the cut at its position (the builder measures spacing as sqrt(area / points) on exactly the
// points drawn there, octree/spacing.h), which radiance-cache VPLs emit from. A point the scan's
// clipping volumes remove keeps its slot but is marked (radius -1, no area, no colour): it then
// occludes nothing, is hit by no bounce and emits nothing.
layout(local_size_x = 128) in;
#include "../../common/point_data.glsl"
#include "../../points/splat_size.glsl"
#include "../../common/clip_volumes.glsl"
#include "vpl_interface.glsl"
layout(std430, binding = VPL_SSBO_POOL) writeonly buffer Pool { PoolPoint pool[]; };
uniform vec3 uNodeOrigin;
uniform int uFirst;
uniform float uRadius, uColourScale;
void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uNumPoints) return;
  vec3 c = min(pointLinearColour(i) * uColourScale, vec3(65504.0));
  PoolPoint q;
  q.position = vec4(uNodeOrigin + pointLocal(i), uRadius);
  if (!clipKeeps(q.position.xyz)) {
    q.position.w = VPL_POOL_CLIPPED;
    q.surface = uvec4(0u, 0u, uint(NL_NO_MATERIAL) << 16, 0u);
    pool[uFirst + int(i)] = q;
    return;
  }
  float s = finestSpacing(pointLocal(i));
  q.surface = uvec4(pointNormalWord(i), packHalf2x16(c.rg), packHalf2x16(vec2(c.b, 0.0)) | (uint(NL_NO_MATERIAL) << 16),
                    floatBitsToUint(s * s));
  pool[uFirst + int(i)] = q;
}
