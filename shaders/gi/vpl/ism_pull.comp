// Pull-push hole filling of the ISMs (Ritschel et al. 2008; Preiner, section 4.3), the pull
// half: each texel of a coarser level is the mean of its valid children (empty: none valid).
layout(local_size_x = 8, local_size_y = 8) in;
#include "ism_pyramid.glsl"
layout(std430, binding = VPL_SSBO_ISM) readonly buffer Ism { uint ism[]; };
float fetch(int v, int level, ivec2 t) {
  return level == 0 ? uintBitsToFloat(ism[atlasIndex(v, t)]) : levels[levelIndex(v, level, t)];
}
void main() {
  ivec2 t = ivec2(gl_GlobalInvocationID.xy);
  int v = uFirstVpl + int(gl_GlobalInvocationID.z);
  int s = uIsmSize >> uLevel;
  if (t.x >= s || t.y >= s) return;
  float sum = 0.0;
  int n = 0;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      float d = fetch(v, uLevel - 1, 2 * t + ivec2(i, j));
      if (d < kFar) sum += d, ++n;
    }
  levels[levelIndex(v, uLevel, t)] = n > 0 ? sum / float(n) : kFar;
}
