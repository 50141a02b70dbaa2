// Basic splats: the nearest splat wins each pixel.
//   0 (default)     the point view's G-buffer: linear colour (decoded by the vertex shader) and
//                   view-space normal; round sprites on request.
//   NL_SCENE_FRAME 1 the GI frame's G-buffer: splats are discs in their tangent planes
//                   (splat_surface.glsl). The depth tested is the splat centre's, not the disc's
//                   under the fragment: discs of one surface overlap about coplanar, and
//                   per-fragment depths would let float rounding pick the winner (the frame
//                   shimmered under tiling and motion). Their material is their colour: emitted
//                   radiance in the radiance-cache mode, a Lambert albedo in the albedo mode.
#include "splat_frame.glsl"
#if NL_SCENE_FRAME
#include "../gi/common/gbuffer_out.glsl"
#include "splat_surface.glsl"
in vec3 vColour;
in vec3 vNormal;
void main() {
  vec3 p;
  float r2;
  if (!splatSurface(p, r2)) discard;
  writeGBuffer(vColour, vRadius, vNormal, NL_MATERIAL_LAMBERT, NL_SOURCE_SCAN, 1.0, 0.0, uint(NL_NO_MATERIAL));
}
#else
in vec4 vColour;
in vec3 vNormal;
uniform bool uRound;

layout(location = 0) out vec4 outColour;
layout(location = 1) out vec4 outNormal;

void main() {
  if (uRound) {
    vec2 d = gl_PointCoord * 2.0 - 1.0;
    if (dot(d, d) > 1.0) discard;
  }
  outColour = vec4(vColour.rgb, 1.0);
  outNormal = vec4(vNormal, dot(vNormal, vNormal) > 0.0 ? 1.0 : 0.0);
}
#endif
