// Importance of every light G-buffer texel into level 0 of its layer's sum pyramid
// (shaders/gi/vpl/light_texel.glsl says what it is).
layout(local_size_x = 8, local_size_y = 8) in;
#include "light_texel.glsl"
layout(std430, binding = VPL_SSBO_PYRAMID) buffer Pyramid { float pyramid[]; };
uniform int uLayerStride;  // floats per layer (all its levels)
void main() {
  ivec3 t = ivec3(gl_GlobalInvocationID);
  int G = textureSize(uLightDepth, 0).x;
  if (t.x >= G || t.y >= G) return;
  float imp = texelImportance(lightTexel(t));
  pyramid[t.z * uLayerStride + t.y * G + t.x] = isinf(imp) || isnan(imp) ? 0.0 : imp;
}
