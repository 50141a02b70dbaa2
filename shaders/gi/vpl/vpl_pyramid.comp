// One level of the importance sum pyramid from the level below (2 x 2 sums), every layer.
layout(local_size_x = 8, local_size_y = 8) in;
#include "../../interface/frame_interface.glsl"
#include "vpl_interface.glsl"
#include "pyramid.glsl"
layout(std430, binding = VPL_SSBO_PYRAMID) buffer Pyramid { float pyramid[]; };
uniform int uSize;   // level 0's side
uniform int uLevel;  // the level written (>= 1)
void main() {
  ivec3 t = ivec3(gl_GlobalInvocationID);
  int s = uSize >> uLevel;
  if (t.x >= s || t.y >= s) return;
  int layer = t.z * pyramidLayerStride(uSize);
  int below = layer + pyramidLevelOffset(uSize, uLevel - 1), here = layer + pyramidLevelOffset(uSize, uLevel);
  int sb = s * 2;
  pyramid[here + t.y * s + t.x] = pyramid[below + (2 * t.y) * sb + 2 * t.x] + pyramid[below + (2 * t.y) * sb + 2 * t.x + 1] +
                                  pyramid[below + (2 * t.y + 1) * sb + 2 * t.x] + pyramid[below + (2 * t.y + 1) * sb + 2 * t.x + 1];
}
