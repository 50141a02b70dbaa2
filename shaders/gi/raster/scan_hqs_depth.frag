// High-quality splatting of the scans into the GI frame's G-buffer (Botsch, Hornung, Zwicker,
// Kobbelt, "High-Quality Surface Splatting on Today's GPUs", 2005, section 3), pass 1 of 3: the
// splats (discs in their tangent planes, splat_surface.glsl) write only depth, pushed back by
// `uDepthEpsilon` splat radii, over the meshes' depth.
#include "splat_surface.glsl"
uniform mat4 uClipFromView;   // the tile's
uniform float uDepthEpsilon;
void main() {
  vec3 p;
  float r2;
  if (!splatSurface(p, r2)) discard;
  gl_FragDepth = windowDepth(uClipFromView, p - vec3(0.0, 0.0, uDepthEpsilon * vRadius));
}
