// Pull-push, the push half: an empty texel takes its parent's value (the parent filled by the
// pull from whatever valid texels lie under it), level by level down to the atlas. Holes wider
// than the levels pulled stay empty (nothing there: the VPL sees through).
layout(local_size_x = 8, local_size_y = 8) in;
#include "ism_pyramid.glsl"
layout(std430, binding = VPL_SSBO_ISM) buffer Ism { uint ism[]; };
void main() {
  ivec2 t = ivec2(gl_GlobalInvocationID.xy);
  int v = uFirstVpl + int(gl_GlobalInvocationID.z);
  int s = uIsmSize >> uLevel;
  if (t.x >= s || t.y >= s) return;
  float parent = levels[levelIndex(v, uLevel + 1, t / 2)];
  if (uLevel == 0) {
    uint i = atlasIndex(v, t);
    if (ism[i] == VPL_FAR_BITS && parent < kFar) ism[i] = floatBitsToUint(parent);
  } else {
    int i = levelIndex(v, uLevel, t);
    if (!(levels[i] < kFar)) levels[i] = parent;
  }
}
