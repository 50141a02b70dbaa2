// High-quality splatting, pass 2 of 3: additive blending of the weighted (hqs_weight.glsl) linear
// colour, normal and view depth of the splat fragments within epsilon of the front surface
// (depth test against pass 1, no depth writes): the pixel gets the kernel-weighted mean of the
// points around it.
//   0 (default)     round sprites, r measured on the sprite; view-space normals (the point view);
//   NL_SCENE_FRAME 1 r measured on the disc (splat_surface.glsl), whose depth under the fragment
//                   is the one tested, as pass 1 wrote it; world normals and the splat radius
//                   too, as the reference's discs average a pixel's area.
#include "splat_frame.glsl"
#include "hqs_weight.glsl"
#if NL_SCENE_FRAME
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
  float w = hqsWeight(r2);
  outColour = vec4(vColour * w, w);
  outNormal = vec4(vNormal * w, -p.z * w);
  outRadius = vec4(vRadius * w, 0.0, 0.0, 0.0);
}
#else
in vec4 vColour;
in vec3 vNormal;
flat in vec3 vViewPos;

layout(location = 0) out vec4 outColour;  // rgb * w, w
layout(location = 1) out vec4 outNormal;  // normal * w, linear depth * w

void main() {
  vec2 d = gl_PointCoord * 2.0 - 1.0;
  float r2 = dot(d, d);
  if (r2 > 1.0) discard;
  float w = hqsWeight(r2);
  outColour = vec4(vColour.rgb * w, w);  // blended in linear light (the vertex shader decodes)
  outNormal = vec4(vNormal * w, -vViewPos.z * w);
}
#endif
