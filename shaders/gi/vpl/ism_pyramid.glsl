// The ISMs' pull-push levels: level 0 is the atlas itself (distances as float bits), levels
// 1.. (each half the last's side) of every ISM follow one another in one float buffer.
#include "../../interface/frame_interface.glsl"
#include "vpl_interface.glsl"
layout(std430, binding = VPL_SSBO_ISM_PYRAMID) buffer IsmPyramid { float levels[]; };
uniform int uIsmSize, uLevel, uFirstVpl;
const float kFar = 3.402823e38;
int levelOffset(int level) {  // within one ISM's levels (1 ..)
  int off = 0;
  for (int l = 1; l < level; ++l) off += (uIsmSize >> l) * (uIsmSize >> l);
  return off;
}
int pyramidStride() {
  int off = 0;
  for (int s = uIsmSize >> 1; s >= 1; s >>= 1) off += s * s;
  return off;
}
uint atlasIndex(int v, ivec2 t) { return uint(v) * uint(uIsmSize * uIsmSize) + uint(t.y * uIsmSize + t.x); }
int levelIndex(int v, int level, ivec2 t) { return v * pyramidStride() + levelOffset(level) + t.y * (uIsmSize >> level) + t.x; }
