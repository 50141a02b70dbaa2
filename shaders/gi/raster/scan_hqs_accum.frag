// High-quality splatting into the G-buffer, pass 2 of 3: additive sums of the linear colour,
// world normal, view depth and splat radius of the splat fragments within epsilon of the front
// surface, each weighted 1 - r^2 (an Epanechnikov kernel, r measured on the disc): the pixel gets
// the kernel-weighted mean of the points around it, as the reference's discs average a pixel's
// area. The depth tested is the disc's under the fragment, as pass 1 wrote it.
#include "splat_surface.glsl"
in vec3 vColour;
in vec3 vNormal;
uniform mat4 uClipFromView;   // the tile's
layout(location = 0) out vec4 outColour;  // rgb w, w
layout(location = 1) out vec4 outNormal;  // normal w, view depth w
layout(location = 2) out vec4 outRadius;  // radius w
void main() {
  vec3 p;
  float r2;
  if (!splatSurface(p, r2)) discard;
  gl_FragDepth = windowDepth(uClipFromView, p);
  float w = max(1.0 - r2, 1.0 / 64.0);
  outColour = vec4(vColour * w, w);
  outNormal = vec4(vNormal * w, -p.z * w);
  outRadius = vec4(vRadius * w, 0.0, 0.0, 0.0);
}
