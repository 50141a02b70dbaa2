// Scan points into the G-buffer: round splats, the nearest wins (depth test). Their material is
// their colour: emitted radiance in the radiance-cache mode, a Lambert albedo in the albedo mode.
#include "../common/gbuffer_out.glsl"
in vec3 vColour;
in vec3 vNormal;
flat in float vRadius;
void main() {
  vec2 d = gl_PointCoord * 2.0 - 1.0;
  if (dot(d, d) > 1.0) discard;
  writeGBuffer(vColour, vRadius, vNormal, NL_MATERIAL_LAMBERT, NL_SOURCE_SCAN, 1.0, 0.0, uint(NL_NO_MATERIAL));
}
